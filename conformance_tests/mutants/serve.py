"""``python -m pltf.conformance_tests.mutants.serve PATCH [reference server options]``: the reference server with one
model patch of patches.py applied first (a model mutant); ``allow:CMD_X:state`` flips one state chart cell."""

from __future__ import annotations

import sys

from pltf.conformance_tests.mutants.patches import PATCHES, allow_in_state


def main(argv: list[str]) -> int:
    if argv and argv[0].startswith("allow:"):  # allow:CMD_X:state - a state chart cell flipped
        _, command, state = argv[0].split(":")
        allow_in_state(command, state)
        from pltf.reference_server.cli import main as serve

        return serve(argv[1:])
    if not argv or argv[0] not in PATCHES:
        print(
            f"usage: python -m pltf.conformance_tests.mutants.serve PATCH [options]; patches: {', '.join(PATCHES)}",
            file=sys.stderr,
        )
        return 2
    PATCHES[argv[0]]()
    from pltf.reference_server.cli import main as serve

    return serve(argv[1:])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
