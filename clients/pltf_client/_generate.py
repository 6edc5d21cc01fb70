"""``python -m pltf.client._generate [--check] [--out DIR]``: rewrite (or check) the generated modules.

``_enums.py``, ``_replies.py`` and ``_commands.py`` are generated from the spec by the toolkit's stub generator
(``pltf.stubgen.pltf_client``: its templates and name helpers, one generator style for every language); this
module only forwards to it. Generation is a development step: the generated modules are committed, and the
client distribution does not need ``pltf.stubgen`` to run (only to regenerate: install the toolkit).
"""

from __future__ import annotations

import importlib
import sys


def main(argv: list[str] | None = None) -> int:
    try:  # by name, not `import`: the client's mypy run and its distribution stay free of the toolkit
        generator = importlib.import_module("pltf.stubgen.pltf_client")
    except ModuleNotFoundError as exc:
        print(
            f"pltf.client._generate: error: needs the toolkit's pltf.stubgen ({exc}); install pltf-toolkit",
            file=sys.stderr,
        )
        return 2
    status: int = generator.main(argv)
    return status


if __name__ == "__main__":
    sys.exit(main())
