"""The generator of the Python client's typed modules (clients/stubgen/pltf_client, pltf.stubgen.pltf_client),
and ``python -m pltf.client._generate`` that forwards to it."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from pltf.client import _generate
from pltf.stubgen.model import Field, messages
from pltf.stubgen.pltf_client import check, main, package_dir, render
from pltf.stubgen.pltf_client.layout import docstring, imports
from pltf.stubgen.pltf_client.names import GeneratorError, check_unique, method_name, py_name, reply_class_name

REPO = Path(__file__).resolve().parents[2]


def _field(message: str, name: str, direction: str = "request") -> Field:
    m = next(m for m in messages(direction) if m.name == message)
    return next(f for f in m.fields if f.name == name)


def test_render_is_the_committed_modules_byte_for_byte() -> None:
    for name, text in render().items():
        assert (REPO / "clients" / "pltf_client" / name).read_bytes() == text.encode("utf-8")
    assert package_dir() == REPO / "clients" / "pltf_client"


def test_check_names_the_stale_and_the_missing_file(tmp_path: Path) -> None:
    assert main(["--out", str(tmp_path)]) == 0
    assert check(tmp_path) == []
    (tmp_path / "_enums.py").write_text("# edited\n", encoding="utf-8")
    (tmp_path / "_replies.py").unlink()
    assert check(tmp_path) == [str(tmp_path / "_enums.py"), str(tmp_path / "_replies.py")]


def test_the_old_command_runs_the_generator(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "pltf.client._generate", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["_commands.py", "_enums.py", "_replies.py"]
    assert (tmp_path / "_commands.py").read_text(encoding="utf-8") == render()["_commands.py"]


def test_without_the_toolkit_the_old_command_says_so_in_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "pltf.stubgen.pltf_client", None)  # as in a client-only install
    assert _generate.main(["--check"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pltf.client._generate: error: needs the toolkit's pltf.stubgen") and err.count("\n") == 1


@pytest.mark.parametrize(
    ("command", "method"),
    [
        ("CMD_MOVE_ABS", "move_abs"),
        ("CMD_BREAK", "break_"),
        ("CMD_CONTINUE", "continue_"),
        ("CMD_GET_STATUS", "get_status"),
    ],
)
def test_method_names(command: str, method: str) -> None:
    assert method_name(command) == method


def test_reply_class_names() -> None:
    assert reply_class_name("CMD_GET_STATUS") == "Status"
    assert reply_class_name("CMD_GET_PLTF_PARAM_VEC") == "PltfParamVec"


def test_field_names_carry_the_unit() -> None:
    angle = _field("CMD_MOVE_ABS", "angle")
    assert angle.unit == "1000*deg" and py_name(angle) == "angle_mdeg"
    assert py_name(replace(angle, unit="%", name="speed_percent")) == "speed_percent"
    assert py_name(replace(angle, unit=None)) == "angle"
    assert py_name(replace(angle, name="index", unit=None), owner="Cluster") == "cluster_index"


def test_an_unknown_unit_stops_the_generator_with_one_line() -> None:
    angle = _field("CMD_MOVE_ABS", "angle")
    with pytest.raises(GeneratorError, match=r"^pltf.client._generate: no Python suffix for unit 'furlong'"):
        py_name(replace(angle, unit="furlong"))
    with pytest.raises(GeneratorError, match=r"CMD_X: duplicate Python names \['x_mm'\]"):
        check_unique(["x_mm", "y_mm", "x_mm"], "CMD_X")


def test_docstrings_take_one_line_when_they_fit() -> None:
    assert docstring("    ", ["Short."], []) == ['    """Short."""']
    lines = docstring("    ", ["Intro."], [("Args", [("x_mm", "word " * 40)])])
    assert lines[0] == '    """Intro.' and lines[2] == "    Args:" and lines[-1] == '    """'
    assert lines[3].startswith("        x_mm: word") and lines[4].startswith("            word")
    assert all(len(line) <= 120 for line in lines)


def test_imports_split_when_too_long() -> None:
    assert imports("m", ["b", "a"]) == ["from m import a, b"]
    long = [f"Name{i:02}" for i in range(20)]
    assert imports("m", long) == ["from m import (", *[f"    {n}," for n in long], ")"]
