"""``pltf gui``: PlatformCtrlGUI in the browser (guide ch. 5), served by the gateway in gui/."""

from __future__ import annotations

import argparse
import asyncio
import logging
import sys
from pathlib import Path

from pltf.cli.options import exit_status, format_host_port, positive, target, target_or_zero
from pltf.gui.recorded import Recording, RecordingError, open_recording
from pltf.gui.serve import Options, serve


def add_gui_arguments(p: argparse.ArgumentParser) -> None:
    platforms = p.add_mutually_exclusive_group(required=True)
    platforms.add_argument(
        "--target",
        type=target,
        action="append",
        metavar="HOST:PORT",
        help="the platform (one of its two ports); repeated: a fleet, every platform on one map (issue 30)",
    )
    platforms.add_argument(
        "--fleet",
        type=Path,
        metavar="FILE",
        help="the fleet file of `pltf serve --fleet FILE`: each platform's first port on --fleet-host, by its name",
    )
    platforms.add_argument(
        "--session",
        type=Path,
        metavar="FILE",
        help="show a recording instead of a platform: a `pltf proxy --record` session file or an MCAP file "
        "(`pltf export --mcap`, `pltf proxy --mcap`), with a timeline; nothing is sent (issue 35)",
    )
    p.add_argument(
        "--fleet-host",
        default="127.0.0.1",
        metavar="HOST",
        help="where the fleet of --fleet listens (`pltf serve --host`; default 127.0.0.1)",
    )
    p.add_argument(
        "--listen",
        type=target_or_zero,
        default="127.0.0.1:8080",
        metavar="HOST:PORT",
        help="where the GUI is served (default 127.0.0.1:8080; port 0: any free port)",
    )
    p.add_argument("--open", action="store_true", help="open the GUI in the default browser")
    p.add_argument(
        "--network-ini",
        type=Path,
        default=None,
        metavar="FILE",
        help="the known addresses (guide 5.2 Network.ini; default ~/.config/pltf/Network.ini)",
    )
    p.add_argument(
        "--reply-timeout",
        type=positive,
        default=None,
        metavar="S",
        help="seconds a request may wait for its reply before the platform counts as silent (default 5)",
    )
    add_door_arguments(p)
    p.epilog = exit_status(
        ok="stopped (Ctrl-C or a signal); a target that does not answer is shown, not an error",
        usage="usage error: bad options, --listen's port in use, a --session file that is not a recording",
    )


def _token(text: str) -> str:
    """argparse type of ``--token``: a secret worth the name (a URL's query carries it: no spaces)."""
    if len(text) < 8 or not text.isprintable() or " " in text or "&" in text or "#" in text:
        raise argparse.ArgumentTypeError("a token of at least 8 characters, without spaces, '&' or '#'")
    return text


def add_door_arguments(p: argparse.ArgumentParser) -> None:
    """Who may drive the platform (issue 33, docs/security.md)."""
    g = p.add_argument_group("who may come in (docs/security.md)")
    g.add_argument(
        "--allow-host",
        action="append",
        default=[],
        metavar="NAME",
        help="also serve requests whose Host is NAME (repeatable; default: the listen address, localhost, loopback)",
    )
    g.add_argument(
        "--allow-target",
        action="append",
        default=[],
        type=target,
        metavar="HOST:PORT",
        help="a platform the page may open besides --target and Network.ini's (repeatable)",
    )
    g.add_argument(
        "--allow-any-target",
        action="store_true",
        help="let the page open any address, and add new ones to Network.ini (Open Socket At)",
    )
    tokens = g.add_mutually_exclusive_group()
    tokens.add_argument(
        "--token",
        type=_token,
        default=None,
        metavar="TOKEN",
        help="the token every request must carry (default beyond loopback: a new one, printed in the URL)",
    )
    tokens.add_argument(
        "--no-token", action="store_true", help="no token even beyond loopback (warned: anyone there can drive)"
    )
    g.add_argument(
        "--read-only",
        action="store_true",
        help="a viewer only: the gateway refuses every command that moves or changes the platform",
    )


def fleet_targets(path: Path, host: str) -> tuple[tuple[str, str], ...]:
    """(name, HOST:PORT) of each platform of a ``pltf serve --fleet`` file: its first port (the GUI holds one of
    the two, guide 4.2) on ``host``. The file is read by the fleet's own parser (reference_server/fleet/config.py,
    imported here: the gateway in gui/ may not import the reference server, the import-linter's gui-codec-only)."""
    from pltf.reference_server.fleet.config import FleetError, load  # only when --fleet is given

    fleet = load(path)  # FleetError: a ValueError with a one-line message naming the file and the platform
    zero = [p.name for p in fleet.platforms if p.ports[0] == 0]
    if zero:
        raise FleetError(
            f"fleet file {path}: platform {zero[0]!r} has port 0 (any free port): the GUI needs "
            "the port it took; give its port in the file, or --target HOST:PORT per platform"
        )
    return tuple((p.name, format_host_port(host, p.ports[0])) for p in fleet.platforms)


def _platforms(args: argparse.Namespace) -> tuple[tuple[str, str], ...]:
    """(name, target) of every platform; a single --target is named by its address."""
    if args.fleet is not None:
        return fleet_targets(args.fleet, args.fleet_host)
    targets = [format_host_port(*t) for t in args.target]
    return tuple((t, t) for t in dict.fromkeys(targets))


def _recording(path: Path | None) -> Recording | None:
    """The recording of --session, indexed once (an hour's session file: a few seconds)."""
    return None if path is None else open_recording(path)


def run_gui(args: argparse.Namespace) -> int:
    try:
        recording = _recording(args.session)
        # a recording: no platform and no target (the gateway has no /ws)
        platforms = _platforms(args) if recording is None else ()
    except (ValueError, RecordingError) as exc:
        print(f"pltf gui: error: {exc}", file=sys.stderr)
        return 2
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)-7s %(message)s")
    return asyncio.run(
        serve(
            platforms[0][1] if platforms else None,
            format_host_port(*args.listen),
            args.network_ini,
            args.open,
            args.reply_timeout,
            Options(
                allow_hosts=tuple(args.allow_host),
                allow_targets=tuple(format_host_port(*t) for t in args.allow_target),
                allow_any_target=args.allow_any_target,
                token=args.token,
                no_token=args.no_token,
                read_only=args.read_only,
            ),
            fleet=platforms if len(platforms) > 1 else (),
            recording=recording,
        )
    )
