"""``pltf stubs``: write (or ``--check``) the generated client of one language (clients/stubgen)."""

from __future__ import annotations

import argparse
import sys

from pltf.stubgen import LANGS, check, generate


def add_stubs_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--lang", required=True, choices=LANGS, help="target language")
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--out", metavar="DIR", help="write the client into DIR (files are overwritten)")
    where.add_argument("--check", metavar="DIR", help="compare DIR with a fresh generation; exit 1 if stale")


def run_stubs(args: argparse.Namespace) -> int:
    if args.check:
        problems = check(args.lang, args.check)
        for problem in problems:
            print(f"{args.check}: {problem}", file=sys.stderr)
        if problems:
            print(f"pltf: {args.lang} stubs in {args.check} are stale; run "
                  f"`pltf stubs --lang {args.lang} --out {args.check}`", file=sys.stderr)
            return 1
        print(f"{args.check}: up to date")
        return 0
    written = generate(args.lang, args.out)
    print(f"{len(written)} files written to {args.out}")
    return 0
