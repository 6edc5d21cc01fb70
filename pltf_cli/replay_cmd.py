"""``pltf replay``: send a recorded session's requests to a target with their recorded timing and compare every
reply with the recorded one, field by field (proxy/replay.py; spec/volatile.yaml for what may differ).

Exit status: 0 when the target answered as recorded, 1 when a difference was found, 2 for an error (the session
file, the arguments, a target that cannot be reached at all).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pltf.cli.options import FAILED, CommandError, exit_status, port, positive, target
from pltf.proxy.replay_io import Settings, run, survey
from pltf.proxy.report import render, write_junit
from pltf.proxy.session import SessionError, open_session


def add_replay_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("session", type=Path, help="a session file written by `pltf proxy --record`")
    p.add_argument(
        "--target", type=target, required=True, metavar="HOST:PORT", help="where to replay the session's first port"
    )
    p.add_argument("--second-port", type=port, metavar="PORT", help="where to replay its second port (if it has one)")
    p.add_argument(
        "--time-scale",
        type=positive,
        default=1.0,
        metavar="X",
        help="replay X times as fast as recorded (default 1: the recorded timing)",
    )
    p.add_argument("--reply-timeout", type=positive, default=3.0, metavar="S", help="seconds to wait for a reply")
    p.add_argument("--junit", type=Path, metavar="FILE", help="write a JUnit XML report")
    p.epilog = exit_status(
        ok="the target answered as recorded",
        failed="a reply differs from the recorded one",
        usage="usage or connection error: an unreadable session file, bad arguments, the target unreachable",
    )


def run_replay(args: argparse.Namespace) -> int:
    try:
        session = open_session(args.session)
        scripts, t0 = survey(session)
    except SessionError as exc:
        raise CommandError(str(exc)) from None
    if not scripts:
        raise CommandError(f"{args.session}: no connection to replay")
    host, port = args.target
    ports = [port]
    if len(session.routes) > 1:
        used = {s.route for s in scripts}
        if 1 in used and args.second_port is None:
            raise CommandError(f"the session used two ports ({session.routes[1].target} too): give --second-port")
        ports.append(args.second_port or port)
    settings = Settings(host, ports, args.time_scale, args.reply_timeout)
    try:
        result, seconds = run(session, scripts, t0, settings)
    except SessionError as exc:  # a line of the file changed since the survey read it
        raise CommandError(str(exc)) from None
    if not result.connected and result.errors:
        raise CommandError(result.errors[0])
    sys.stdout.write(render(result.differences, result.counts))
    if args.junit is not None:
        try:
            write_junit(args.junit, result.differences, result.telegrams, seconds)
        except OSError as exc:
            raise CommandError(f"cannot write {args.junit}: {exc.strerror}") from None
    return FAILED if result.differences else 0
