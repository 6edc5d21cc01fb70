"""The errata register is well formed and every erratum cited anywhere in the project exists."""

from __future__ import annotations

from pathlib import Path

from pltf.spec.errata import cited_ids, errata_for, load_errata
from pltf.spec.model import load_telegrams

ROOT = Path(__file__).resolve().parents[2]
SOURCES = ["spec", "reference_server", "fake_hardware", "conformance_tests", "fuzz", "clients/stubgen", "pltf_cli"]


def test_register_loads_with_unique_ids() -> None:
    errata = load_errata()
    assert len(errata) >= 60
    assert {e.topic for e in errata.values()} >= {"wire", "parameters", "xml"}


def test_every_cited_erratum_exists() -> None:
    known = set(load_errata())
    for folder in SOURCES:
        for path in (ROOT / folder).rglob("*"):
            if path.suffix in {".py", ".yaml", ".xsd"} and "errata" not in path.parts:
                missing = cited_ids(path.read_text(encoding="utf-8")) - known
                assert not missing, f"{path.relative_to(ROOT)} cites unknown errata {sorted(missing)}"


def test_applies_to_names_real_telegrams() -> None:
    names = {t.name for t in load_telegrams()} | {a for t in load_telegrams() for a in t.aliases}
    for e in load_errata().values():
        assert set(e.applies_to) <= names, e.id


def test_known_contradictions_of_the_field_evidence_are_decided() -> None:
    # field-evidence.md "Known gaps and contradictions": each has a decision on record.
    for telegram in (
        "CMD_GET_STATUS",
        "CMD_GET_MAP",
        "CMD_GET_ROADMAP",
        "CMD_GET_PROGRAM",
        "CMD_GET_PLTF_PARAM",
        "CMD_GET_CAN_MESSAGES",
        "CMD_SET_LOG_ENABLED",
        "CMD_SET_POST_PROCESS_FILENAME",
        "CMD_GET_DEBUG_DATA",
        "CMD_MOVE_VEL",
        "CMD_GET_POSITION",
    ):
        assert errata_for(telegram), telegram
    sections = " ".join(f"{e.section} {e.guide} {e.problem}" for e in load_errata().values())
    for topic in ("Version", "edge", "wait", "layer"):
        assert topic.lower() in sections.lower(), topic
