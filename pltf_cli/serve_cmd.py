"""``pltf serve``: run the reference server (reference_server.cli)."""

from __future__ import annotations

import argparse

from pltf.cli.options import exit_status
from pltf.reference_server import cli


def add_serve_arguments(p: argparse.ArgumentParser) -> None:
    cli.add_arguments(p)
    p.epilog = exit_status(
        ok="stopped by CMD_EXIT or a signal",
        usage="usage error: bad options, an unusable data dir or CAN interface, a port in use",
    )


def run_serve(args: argparse.Namespace) -> int:
    return cli.run(args, "pltf serve")
