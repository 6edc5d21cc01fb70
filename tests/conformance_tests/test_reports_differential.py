"""The differential session in every report (issue 34): JSON, JUnit and HTML carry its fields grouped by reply and
field (the same difference in six states is one entry with a count), and a difference zoo/emulator_differences.yaml
documents is named with its errata. Before, only the console showed the diffs, one line each."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from pltf.cli.main import main
from pltf.conformance_tests.differential import Diff
from pltf.conformance_tests.reports.differential import Differential
from pltf.conformance_tests.reports.files import write_json, write_junit
from pltf.conformance_tests.reports.html import write_html
from pltf.conformance_tests.runner import RunResult
from pltf.conformance_tests.target import Config, Target
from pltf.harness import launch
from tests.emulator_gate import emulator_or_skip

VEC = "CMD_GET_PLTF_PARAM_VEC()"


def _session() -> Differential:
    """Six states that answer the parameter count of the emulator, and one status field that differs twice."""
    diffs = [Diff(10 * i, VEC, "parameters (count)", 104, 103) for i in range(6)]
    diffs += [Diff(7, "CMD_GET_STATUS()", "motion_mode", 3, 0), Diff(9, "CMD_GET_STATUS()", "motion_mode", 2, 0)]
    return Differential(200, diffs)


def test_repeated_differences_are_grouped_by_field_with_a_count() -> None:
    vec, mode = _session().groups()
    assert (vec.reply, vec.path, vec.count, vec.pairs) == (
        "CMD_GET_PLTF_PARAM_VEC",
        "parameters (count)",
        6,
        ((104, 103, 6),),
    )
    assert vec.documented is not None and vec.documented.errata == ("E-PAR-018", "E-PAR-024")
    assert (mode.count, mode.pairs, mode.documented) == (2, ((3, 0, 1), (2, 0, 1)), None)
    assert "2 field(s) differ" in _session().summary() and "1 field(s) documented" in _session().summary()


def test_a_documented_field_with_other_values_is_not_documented() -> None:
    (group,) = Differential(1, [Diff(1, VEC, "parameters (count)", 104, 90)]).groups()
    assert group.documented is None


def _run() -> RunResult:
    config = Config("127.0.0.1", 1)
    return RunResult(config, [], Target(config), 0.0, 1.0)


def test_json_junit_and_html_carry_the_grouped_fields(tmp_path: Path) -> None:
    run, session = _run(), _session()
    write_json(run, tmp_path / "r.json", session)
    write_junit(run, tmp_path / "r.xml", session)
    write_html(run, tmp_path / "r.html", session)
    section = json.loads((tmp_path / "r.json").read_text())["differential"]
    assert (section["steps"], section["differences"], section["exit_code"]) == (200, 8, 1)
    vec = section["fields"][0]
    assert (vec["reply"], vec["field"], vec["count"]) == ("CMD_GET_PLTF_PARAM_VEC", "parameters (count)", 6)
    assert vec["values"] == [{"reference": 104, "target": 103, "count": 6}]
    assert vec["documented"]["errata"] == ["E-PAR-018", "E-PAR-024"]
    suite = next(s for s in ET.parse(tmp_path / "r.xml").getroot() if s.get("name", "").startswith("differential"))
    names = [tc.get("name") for tc in suite.findall("testcase")]
    assert names == ["CMD_GET_PLTF_PARAM_VEC parameters (count)", "CMD_GET_STATUS motion_mode"]
    assert suite.get("failures") == "2" and len(suite.findall("testcase/failure")) == 2
    assert "E-PAR-024" in (suite.findall("testcase/system-out")[0].text or "")
    html = (tmp_path / "r.html").read_text()
    assert "Differential session" in html and "parameters (count)" in html and "E-PAR-018" in html


def test_no_differential_run_is_null_in_json_and_absent_elsewhere(tmp_path: Path) -> None:
    write_json(_run(), tmp_path / "r.json")
    write_junit(_run(), tmp_path / "r.xml")
    assert json.loads((tmp_path / "r.json").read_text())["differential"] is None
    assert not [s for s in ET.parse(tmp_path / "r.xml").getroot() if s.get("name", "").startswith("differential")]


def test_the_emulator_differential_reaches_the_json_report(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """End to end: ``pltf conform --differential --json`` against the Go emulator: the documented parameter
    count is one field with its count in the JSON, and the console shows it once, not once per state."""
    emulator_or_skip()
    with launch.emulator(time_scale=10.0) as emu:
        code = main(
            [
                "conform",
                "--target",
                f"127.0.0.1:{emu.ports[0]}",
                "--second-port",
                str(emu.ports[1]),
                "--time-scale",
                "10",
                "--profile",
                "original",
                "-k",
                "6.1/ports/reconnect",
                "--differential",
                "--json",
                str(tmp_path / "r.json"),
            ]
        )
    out = capsys.readouterr().out
    assert code == 1, out  # a difference fails the run, as before
    fields = json.loads((tmp_path / "r.json").read_text())["differential"]["fields"]
    counted = {(f["reply"], f["field"]): f for f in fields}
    vec = counted[("CMD_GET_PLTF_PARAM_VEC", "parameters (count)")]
    assert vec["count"] > 1 and vec["values"] == [{"reference": 104, "target": 103, "count": vec["count"]}]
    assert vec["documented"]["source"] == "zoo/emulator_differences.yaml"
    assert out.count("parameters (count)") == 1
