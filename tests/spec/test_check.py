"""pltf.spec.check: the JSON Schema validation of the spec data, run by docgen --check instead of every load."""

from __future__ import annotations

import copy
from typing import Any

import pytest

from pltf.spec import docgen
from pltf.spec.check import check_spec, problems
from pltf.spec.model import load_yaml


def test_the_spec_data_is_valid() -> None:
    assert check_spec() == []


@pytest.mark.parametrize(
    ("breakage", "where"),
    [
        (lambda d: d["telegrams"][3].update(id=300), "telegrams/3/id"),
        (lambda d: d["telegrams"][0].pop("summary"), "telegrams/0"),
        (
            lambda d: d["telegrams"][5]["request"].append({"name": "Bad Name", "type": "INT", "description": "x"}),
            "telegrams/5/request/1/name",
        ),
    ],
)
def test_a_broken_telegram_table_is_named_where_it_breaks(breakage: Any, where: str) -> None:
    data = copy.deepcopy(load_yaml("telegrams.yaml"))
    breakage(data)
    found = problems(data, "telegrams.schema.json")
    assert found and all(p.startswith("telegrams.schema.json: ") for p in found)
    assert any(p.split(": ")[1].startswith(where) for p in found), found


def test_docgen_check_fails_on_schema_problems(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(docgen, "check_spec", lambda: ["telegrams.schema.json: telegrams/3/id: 300 is too big"])
    assert docgen.main(["--check"]) == 1
    assert "spec: telegrams.schema.json: telegrams/3/id" in capsys.readouterr().err
