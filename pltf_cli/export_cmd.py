"""``pltf export``: a recorded session (``pltf proxy --record``) in another format: ``--mcap OUT`` writes MCAP
with Foxglove's well-known schemas (proxy/mcap_export.py), for Foxglove, Lichtblick and the ROS 2 tools.

Exit status 0, or 2 for a user error (an unreadable session file, an unwritable output).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from pltf.cli.options import CommandError, exit_status
from pltf.proxy.mcap_export import COMPRESSION_NAMES, DEFAULT_COMPRESSION, export_session
from pltf.proxy.session import SessionError


def add_export_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("session", type=Path, help="a session file written by `pltf proxy --record`")
    p.add_argument(
        "--mcap",
        type=Path,
        required=True,
        metavar="OUT",
        help="write the session as MCAP to OUT (written to a temporary file beside it, then renamed)",
    )
    p.add_argument(
        "--compression",
        choices=COMPRESSION_NAMES,
        default=DEFAULT_COMPRESSION,
        help="how each chunk of the MCAP file is compressed (default: %(default)s; zstd makes a smaller file more "
        "slowly; Foxglove reads all three)",
    )
    p.epilog = exit_status(ok="written", usage="usage error: an unreadable session file, the output not writable")


def run_export(args: argparse.Namespace) -> int:
    try:
        counts = export_session(args.session, args.mcap, compression=args.compression)
    except SessionError as exc:
        raise CommandError(str(exc)) from None
    except OSError as exc:
        raise CommandError(f"cannot write {args.mcap}: {exc.strerror or exc}") from None
    channels = ", ".join(f"{topic} {n}" for topic, n in counts.items())
    print(f"{args.mcap}: {sum(counts.values())} messages ({channels})")
    return 0
