"""``pltf fuzz``: the protocol fuzzer (fuzz/); exit 0 nothing found, 1 findings written to --out, 2 harness error.

The arguments are checked before anything is created: --out appears with the first finding or the summary. A
target that does not answer at the start is named by its port, the flag that gave it and what was seen
(pltf.fuzz.profile, pltf.fuzz.engine).
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import sys
from pathlib import Path
from typing import Any

from pltf.cli.options import CommandError, count, exit_status, port, positive, target_or_zero


def add_fuzz_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--target",
        type=target_or_zero,
        metavar="HOST:PORT",
        help="the port to fuzz (port 0 with --launch: "
        "ephemeral ports read from the target's 'server started at port N' lines)",
    )
    p.add_argument(
        "--second-port",
        type=port,
        metavar="PORT",
        help="port of the liveness probe (default: PORT+2, guide 6.1 10000/10002)",
    )
    p.add_argument(
        "--duration", type=positive, default=60.0, metavar="SECONDS", help="wall seconds to fuzz (default 60)"
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the case generator (default 0): same seed, same cases")
    p.add_argument("--out", type=Path, default=Path("fuzz-findings"), metavar="DIR", help="findings are written here")
    p.add_argument("--corpus", type=Path, metavar="DIR", help="resume from / save progress and interesting inputs")
    p.add_argument(
        "--allow-motion",
        action="store_true",
        help="also send the telegrams that make a platform move, and fuzz in Running/Breaked",
    )
    p.add_argument("--in-process", action="store_true", help="fuzz spec.codec and the XML validation directly")
    p.add_argument(
        "--launch",
        metavar="CMD",
        help="start (and restart) the target with CMD; {port} {second_port} "
        "{ports} {tmpdir} are replaced. Needed to minimize deaths and hangs.",
    )
    p.add_argument("--deadline", type=positive, default=2.0, metavar="SECONDS", help="liveness and reply deadline")
    p.add_argument("--max-cases", type=count, metavar="N", help="stop after this many cases")
    p.add_argument("--max-findings", type=count, metavar="N", help="stop after this many findings")
    p.add_argument(
        "--minimize-seconds",
        type=positive,
        default=60.0,
        metavar="SECONDS",
        help="time budget of one delta debugging (default 60)",
    )
    p.add_argument(
        "--probe-every",
        type=int,
        default=4,
        metavar="UNITS",
        help="every case opens with a request whose answer proves the target served it (the liveness "
        "probe); once 256 were served and none turned away, one case in UNITS of those that owe no "
        "answer keeps it (1: every case)",
    )
    p.add_argument(
        "--lanes",
        type=int,
        choices=(1, 2),
        default=2,
        help="2: cases run on both ports at once; 1: one at a time on --target's port",
    )
    p.add_argument(
        "--no-pipeline",
        action="store_true",
        help="connect a port's next case only after the target closed the last one (default: up to 3 "
        "small cases wait behind it while the target serves them in turn)",
    )
    p.add_argument(
        "--big-share",
        type=_share,
        default=None,
        metavar="FRACTION",
        help="of the cases over 1 MiB drawn, the share kept (default 0.25; 1: the natural mix)",
    )
    p.add_argument(
        "--jobs",
        type=_jobs,
        default=1,
        metavar="N",
        help="N workers, each with its own target from --launch and seed SEED+k, sharing what they find "
        "interesting; findings once, one report (default 1)",
    )
    p.add_argument(
        "--ray",
        metavar="ADDRESS",
        help="run the --jobs workers as Ray actors on the cluster at ADDRESS ('auto': the local one); "
        "needs pip install 'pltf-toolkit[ray]'",
    )
    p.add_argument("--quiet", action="store_true", help="no live view")
    p.epilog = exit_status(
        ok="nothing found",
        failed="findings written to --out",
        usage="usage or connection error: bad arguments, nothing listening on --target or the "
        "probe port, the launch command failed",
    )


def _share(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number from 0 to 1, got {text!r}") from None
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"expected a number from 0 to 1, got {text!r}")
    return value


def _jobs(text: str) -> int:
    value = count(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return value


def _check_out(out: Path) -> None:
    """--out is created when the first finding (or the summary) is written; here only checked that it can be."""
    if out.exists() and not out.is_dir():
        raise CommandError(f"--out {out}: not a directory")
    parent = next((d for d in (out, *out.parents) if d.exists()), Path("."))
    if not os.access(parent, os.W_OK | os.X_OK):
        raise CommandError(f"--out {out}: {parent} is not writable")


def run_fuzz(args: argparse.Namespace) -> int:
    _check_out(args.out)
    command = "pltf " + " ".join(shlex.quote(a) for a in sys.argv[1:])
    if args.in_process:
        return _in_process(args, command)
    if args.target is None:
        raise CommandError("--target HOST:PORT is required (or --in-process)")
    host, port = args.target
    if port == 0 and not args.launch:
        raise CommandError("--target port 0 (the ports the target reports) needs --launch")
    if host not in ("127.0.0.1", "localhost", "::1") and args.launch:
        raise CommandError("--launch needs a loopback --target")
    second = args.second_port if args.second_port is not None else (0 if port == 0 else port + 2)
    if second > 65535:
        raise CommandError(f"--second-port: the default, PORT+2 = {second}, is over 65535: give one")

    from pltf.fuzz.engine import Campaign, HarnessError, Options
    from pltf.fuzz.view import LiveView
    from pltf.harness.launch import LaunchError

    opts = Options(
        host=host,
        port=port,
        second_port=second,
        duration=args.duration,
        seed=args.seed,
        out=args.out,
        corpus=args.corpus,
        allow_motion=args.allow_motion,
        launch=args.launch,
        max_cases=args.max_cases,
        max_findings=args.max_findings,
        deadline=args.deadline,
        minimize_seconds=args.minimize_seconds,
        command=command,
        probe_every=max(1, args.probe_every),
        lanes=args.lanes,
        pipeline=not args.no_pipeline,
    )
    if args.big_share is not None:
        opts.big_share = args.big_share
    if args.jobs > 1 or args.ray:
        return _parallel(args, opts)
    campaign = Campaign(opts)
    try:
        with LiveView(f"pltf fuzz {host}:{port}", args.quiet) as view:
            campaign.on_tick = view.update
            code = campaign.run()
    except HarnessError as exc:  # at the start: the message names the port, the flag and what was seen
        campaign.close()
        raise CommandError(str(exc)) from None
    except (LaunchError, OSError) as exc:
        campaign.close()
        raise CommandError(str(exc)) from None
    view.final(campaign.stats)
    _summary(args.out, campaign.stats)
    return code


def _parallel(args: argparse.Namespace, opts: Any) -> int:
    """--jobs N (worker processes) or --ray ADDRESS (Ray actors): one client per port, so a target each."""
    if not args.launch:
        raise CommandError(
            f"--jobs {args.jobs}{' --ray' if args.ray else ''} needs --launch CMD: a target serves one client per "
            "port (guide 6.1), so each worker starts its own"
        )
    from pltf.fuzz.engine import HarnessError
    from pltf.fuzz.parallel import LocalCampaign
    from pltf.fuzz.view import LiveView
    from pltf.harness.launch import LaunchError

    title = f"pltf fuzz --jobs {args.jobs}" + (f" --ray {args.ray}" if args.ray else "")
    try:
        if args.ray:
            from pltf.fuzz.ray_fuzz import RayCampaign

            campaign: Any = RayCampaign(opts, args.jobs, args.ray)
        else:
            campaign = LocalCampaign(opts, args.jobs)
        campaign.start()  # the workers start before the live view's thread does (fork)
        with LiveView(title, args.quiet) as view:
            campaign.on_tick = view.update
            code: int = campaign.run()
    except (HarnessError, LaunchError, OSError) as exc:
        raise CommandError(str(exc)) from None
    view.final(campaign.view)
    return code


def _in_process(args: argparse.Namespace, command: str) -> int:
    from pltf.fuzz.inprocess import InProcessCampaign
    from pltf.fuzz.view import LiveView

    ip = InProcessCampaign(args.seed, args.duration, args.out, args.max_cases, args.deadline, command)
    with LiveView("pltf fuzz --in-process", args.quiet) as view:
        code = ip.run(view.update)
    view.final(ip.stats)
    _summary(args.out, ip.stats)
    return code


def _summary(out: Path, stats: object) -> None:
    s = stats
    doc = {
        "profile": getattr(s, "profile", None) or None,  # what the opening phase learnt (pltf.fuzz.profile)
        "cases": s.cases,  # type: ignore[attr-defined]
        "seconds": round(s.elapsed, 3),  # type: ignore[attr-defined]
        "cases_per_second": round(s.rate, 1),  # type: ignore[attr-defined]
        "origins": dict(s.origins),  # type: ignore[attr-defined]
        "telegrams": sorted(s.telegrams),  # type: ignore[attr-defined]
        "states": sorted(str(x) for x in getattr(s, "states", ())),
        "findings": s.findings,  # type: ignore[attr-defined]
        "unconfirmed": getattr(s, "unconfirmed", []),
        "units": {k: getattr(s, k, None) for k in ("batches", "singles", "probes", "restarts", "duplicates")},
        "replies_cut_by_a_refusal": getattr(s, "cut_replies", None),
        "dropped_unsafe": getattr(s, "dropped_unsafe", None),
        "pipelining": {k: getattr(s, k, None) for k in ("pipelined", "turn_aways", "turned_away")},
        "connections": {
            "not_admitted": getattr(s, "not_admitted", None),  # turned away or left in a backlog: run again
            "release_ms": getattr(s, "release_ms", None),  # per port: median wait for a fresh connection
            "dear": getattr(s, "dear", None),  # batches on a kept connection, singles skipped beyond a queue
            "singles_skipped": getattr(s, "skipped", None),
            "ways": getattr(s, "ways", None),  # cases/s with fresh connections and the dear way (fuzz.trial)
        },
        "replays": getattr(s, "replays", None),
    }
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(doc, indent=2) + "\n")
