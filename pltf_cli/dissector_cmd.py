"""``pltf dissector``: write the Wireshark Lua dissector generated from spec/ (or ``--check`` a copy of it)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pltf.cli.options import FAILED, CommandError, exit_status
from pltf.proxy.dissector import check, render


def add_dissector_arguments(p: argparse.ArgumentParser) -> None:
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--out", type=Path, metavar="FILE", help="write the dissector to FILE (e.g. pltf.lua)")
    where.add_argument("--check", type=Path, metavar="FILE", help="exit 1 if FILE differs from a fresh generation")
    p.epilog = exit_status(
        ok="written (--check: up to date)",
        failed="--check: FILE differs from a fresh generation",
        usage="usage error: --out not writable, --check FILE unreadable",
    )


def run_dissector(args: argparse.Namespace) -> int:
    if args.check is not None:
        if not args.check.is_file():
            raise CommandError(f"--check {args.check}: no such file")
        problem = check(args.check)
        if problem:
            print(f"pltf dissector: {problem}", file=sys.stderr)
            return FAILED
        print(f"{args.check}: up to date")
        return 0
    try:
        args.out.write_text(render(), encoding="utf-8")
    except OSError as exc:
        raise CommandError(f"cannot write {args.out}: {exc.strerror}") from None
    print(f"wrote {args.out} (Wireshark: wireshark -X lua_script:{args.out}, or copy it into the Lua plugins folder)")
    return 0
