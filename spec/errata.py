"""The errata register: every ambiguity or contradiction of the guide, with our decision.

The register is the folder ``spec/errata/`` (one YAML file per topic: wire, parameters, xml, ...), each a
list of entries validated against ``errata.schema.json``. The conformance suite reads ``level`` and the
alternatives' ``original_profile`` to grade a target; the docs generator renders it.
"""

from __future__ import annotations

import functools
import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import jsonschema
import yaml

from pltf.spec.model import SPEC_DIR, SpecError

ERRATA_DIR = SPEC_DIR / "errata"
ERRATUM_ID = re.compile(r"\bE-[A-Z]+-\d{3}\b")
Level = Literal["MUST", "SHOULD", "MAY"]


@dataclass(frozen=True)
class Alternative:
    reading: str
    accepted_by_original_profile: bool


@dataclass(frozen=True)
class Erratum:
    id: str
    topic: str
    section: str
    guide: str
    problem: str
    decision: str
    reason: str
    alternatives: tuple[Alternative, ...]
    level: Level
    applies_to: tuple[str, ...]


def _entries(path: Path, validator: jsonschema.Draft202012Validator) -> list[Erratum]:
    raw = yaml.safe_load(path.read_text(encoding="utf-8"))
    errors = sorted(validator.iter_errors(raw), key=lambda e: list(e.absolute_path))
    if errors:
        where = "/".join(str(p) for p in errors[0].absolute_path)
        raise SpecError(f"{path.name}: {where}: {errors[0].message}")
    return [
        Erratum(
            id=e["id"],
            topic=path.stem,
            section=e["section"],
            guide=e["guide"],
            problem=e["problem"],
            decision=e["decision"],
            reason=e["reason"],
            alternatives=tuple(Alternative(a["reading"], a["original_profile"] == "accept") for a in e["alternatives"]),
            level=e["level"],
            applies_to=tuple(e.get("applies_to", ())),
        )
        for e in raw
    ]


@functools.cache
def load_errata() -> dict[str, Erratum]:
    """Every erratum by id, in file then entry order; ids are unique across the register."""
    schema = json.loads((SPEC_DIR / "errata.schema.json").read_text(encoding="utf-8"))
    validator = jsonschema.Draft202012Validator(schema)
    out: dict[str, Erratum] = {}
    for path in sorted(ERRATA_DIR.glob("*.yaml")):
        for entry in _entries(path, validator):
            if entry.id in out:
                raise SpecError(f"{path.name}: duplicate erratum id {entry.id}")
            out[entry.id] = entry
    return out


def errata_for(telegram: str) -> list[Erratum]:
    """The errata that concern one telegram (by name)."""
    return [e for e in load_errata().values() if telegram in e.applies_to]


def cited_ids(text: str) -> set[str]:
    """Erratum ids cited in a piece of text (spec data, source code)."""
    return set(ERRATUM_ID.findall(text))
