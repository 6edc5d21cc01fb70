"""``pltf serve``: run the reference server (reference_server.cli)."""

from __future__ import annotations

import argparse

from pltf.reference_server import cli


def add_serve_arguments(p: argparse.ArgumentParser) -> None:
    cli.add_arguments(p)


def run_serve(args: argparse.Namespace) -> int:
    return cli.run(args)
