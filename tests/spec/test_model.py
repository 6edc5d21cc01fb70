"""pltf.spec.model: lookups over the telegram definitions."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from pltf.spec import docgen, model
from pltf.spec.compiler import distance_from_end
from pltf.spec.model import json_copy, load_data, load_telegrams, load_yaml, telegram_def


def test_telegram_def_finds_every_telegram_by_name() -> None:
    for t in load_telegrams():
        assert telegram_def(t.name) == t
    with pytest.raises(KeyError):
        telegram_def("CMD_NO_SUCH_THING")


def test_the_status_timestamp_sits_at_a_fixed_distance_from_the_end() -> None:
    layout = telegram_def("CMD_GET_STATUS").layout("reply") or ()
    names = [f.name for f in layout]
    distance = distance_from_end(layout, "timestamp")
    assert distance is not None and distance >= 4
    assert distance_from_end(layout, "scan") is None  # a group: its size depends on the data
    assert distance_from_end(layout, names[-1]) == 4  # head_position, one INT


@pytest.mark.parametrize("name", ["telegrams.yaml", "enums.yaml"])
def test_the_committed_json_copy_is_the_yaml_and_is_what_loads(name: str) -> None:
    assert json_copy(name).read_text(encoding="utf-8") == model.render_json_copy(name), "run python -m pltf.spec.docgen"
    assert load_data(name) == load_yaml(name)


def test_a_yaml_edited_after_its_copy_is_read_from_the_yaml(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    for name in ("enums.yaml", "enums.json"):
        shutil.copy(model.SPEC_DIR / name, tmp_path / name)
    monkeypatch.setattr(model, "SPEC_DIR", tmp_path)
    assert load_data("enums.yaml") == load_yaml("enums.yaml")
    yaml_path = tmp_path / "enums.yaml"
    yaml_path.write_text(
        yaml_path.read_text(encoding="utf-8").replace("MODE_MOTION_VEL", "MODE_MOTION_VELOCITY"), encoding="utf-8"
    )
    edited = load_data("enums.yaml")
    assert "MODE_MOTION_VELOCITY" in str(edited) and edited == load_yaml("enums.yaml")
    (tmp_path / "enums.json").write_text("{not json", encoding="utf-8")
    assert load_data("enums.yaml") == edited


def test_docgen_check_names_a_stale_copy(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    stale = tmp_path / "telegrams.json"
    stale.write_text("{}", encoding="utf-8")
    monkeypatch.setattr(docgen, "json_copy", lambda name: stale if name == "telegrams.yaml" else json_copy(name))
    assert docgen.main(["--check"]) == 1
    assert f"{stale} is stale: run `python -m pltf.spec.docgen`" in capsys.readouterr().err
