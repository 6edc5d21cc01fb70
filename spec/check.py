"""Validate the spec's own data (telegrams.yaml, enums.yaml) against their JSON Schemas.

``python -m pltf.spec.check`` (and ``python -m pltf.spec.docgen --check``, which ``make test`` runs) exits 1
with one line per problem. The loader (pltf.spec.model) does not run this: the files are package data, fixed
at release, so they are checked where they are edited, not in every process that decodes a frame (see the
model's docstring). Needs jsonschema: the ``check`` extra of pltf-spec (the toolkit installs it).
"""

from __future__ import annotations

import json
import sys
from typing import Any

from pltf.spec.model import SPEC_DIR, load_yaml

# data file -> its schema
SCHEMAS = {"telegrams.yaml": "telegrams.schema.json", "enums.yaml": "enums.schema.json"}


def problems(data: Any, schema_name: str) -> list[str]:
    """Every place where ``data`` breaks the schema ``schema_name``, as ``schema: path: message``."""
    import jsonschema

    schema = json.loads((SPEC_DIR / schema_name).read_text(encoding="utf-8"))
    validator = jsonschema.Draft202012Validator(schema)
    found = sorted(validator.iter_errors(data), key=lambda e: [str(p) for p in e.absolute_path])
    return [f"{schema_name}: {'/'.join(str(p) for p in e.absolute_path) or '(top)'}: {e.message}" for e in found]


def check_spec() -> list[str]:
    """The schema problems of every spec data file (empty when all are valid)."""
    return [line for data_file, schema in SCHEMAS.items() for line in problems(load_yaml(data_file), schema)]


def main() -> int:
    found = check_spec()
    for line in found:
        print(f"spec: {line}", file=sys.stderr)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
