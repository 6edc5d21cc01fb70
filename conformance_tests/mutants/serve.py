"""``python -m conformance_tests.mutants.serve PATCH [reference server options]``: the reference server with one
model patch of patches.py applied first (a model mutant)."""

from __future__ import annotations

import sys

from conformance_tests.mutants.patches import PATCHES


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in PATCHES:
        print(f"usage: python -m conformance_tests.mutants.serve PATCH [options]; patches: {', '.join(PATCHES)}",
              file=sys.stderr)
        return 2
    PATCHES[argv[0]]()
    from reference_server.cli import main as serve

    return serve(argv[1:])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
