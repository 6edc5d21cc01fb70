"""``pltf stubs``: write (or ``--check``) the generated client of one language (clients/stubgen)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pltf.cli.options import FAILED, CommandError, exit_status
from pltf.stubgen import LANGS, check, generate


def add_stubs_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--lang", required=True, choices=LANGS, help="target language")
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--out", metavar="DIR", help="write the client into DIR (files are overwritten)")
    where.add_argument("--check", metavar="DIR", help="compare DIR with a fresh generation; exit 1 if stale")
    p.epilog = exit_status(
        ok="written (--check: up to date)",
        failed="--check: DIR differs from a fresh generation",
        usage="usage error: bad options, --out not writable, --check DIR not a directory",
    )


def run_stubs(args: argparse.Namespace) -> int:
    if args.check:
        if not Path(args.check).is_dir():
            raise CommandError(f"--check {args.check}: not a directory")
        problems = check(args.lang, args.check)
        for problem in problems:
            print(f"{args.check}: {problem}", file=sys.stderr)
        if problems:
            print(
                f"pltf stubs: {args.lang} stubs in {args.check} are stale; run "
                f"`pltf stubs --lang {args.lang} --out {args.check}`",
                file=sys.stderr,
            )
            return FAILED
        print(f"{args.check}: up to date")
        return 0
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise CommandError(f"--out {args.out}: not a directory")
    written = generate(args.lang, args.out)
    print(f"{len(written)} files written to {args.out}")
    return 0
