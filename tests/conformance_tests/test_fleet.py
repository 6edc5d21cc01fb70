"""``pltf conform --targets FILE`` (issue 34): a fleet of four - the reference server, the Go emulator and two zoo
members (faithful in front of a reference server, slow-release-rst in front of an emulator) - checked at once
gives one report, each target's verdicts identical to a single run against it, and a matrix that names the
documented differences between them. The default tier runs a few cases; the slow tier the whole standard tier."""

from __future__ import annotations

import contextlib
import json
import socket
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from pltf.cli.main import main
from pltf.harness import launch
from tests.emulator_gate import emulator_or_skip

TIME_SCALE = 10.0
# a framing case all pass; the errata-parameters case the emulator answers N/A (E-PAR-024, documented in
# zoo/emulator_differences.yaml); the second client the emulator leaves in the backlog (NON-STRICT, E-WIRE-007)
FEW = "6.2/framing/header-and-length or 5.9/parameters/errata-parameters or 6.1/ports/second-client-turned-away"
PROFILES = {"reference": "strict", "emulator": "original", "faithful": "strict", "slow-release-rst": "original"}
UPSTREAM = {"faithful": "reference", "slow-release-rst": "emulator"}  # an emulator starts in 0.2 s, a server in 5


def _start(name: str) -> launch.Launched:
    if name == "reference":
        return launch.reference(time_scale=TIME_SCALE)
    if name == "emulator":
        return launch.emulator(time_scale=TIME_SCALE)
    return launch.zoo(name, upstream=UPSTREAM[name], time_scale=TIME_SCALE)


@pytest.fixture(scope="module")
def four(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Path, dict[str, launch.Launched]]]:
    """The four targets, running, and a fleet file that names them."""
    emulator_or_skip()
    with contextlib.ExitStack() as stack:
        started = {name: stack.enter_context(_start(name)) for name in PROFILES}
        entries = [
            {"name": n, "target": f"127.0.0.1:{t.ports[0]}", "second_port": t.ports[1], "profile": PROFILES[n]}
            for n, t in started.items()
        ]
        path = tmp_path_factory.mktemp("fleet") / "fleet.yaml"
        defaults = {"time_scale": TIME_SCALE, "target_is_simulator": True}
        path.write_text(yaml.safe_dump({"defaults": defaults, "targets": entries}), encoding="utf-8")
        yield path, started


def _single(target: launch.Launched, profile: str, keyword: str | None, out: Path) -> tuple[int, dict[str, str]]:
    args = ["conform", "--target", f"127.0.0.1:{target.ports[0]}", "--second-port", str(target.ports[1])]
    args += ["--time-scale", f"{TIME_SCALE:g}", "--target-is-simulator", "--profile", profile, "--json", str(out)]
    code = main(args + (["-k", keyword] if keyword else []))
    return code, {c["id"]: c["verdict"] for c in json.loads(out.read_text())["cases"]}


def check_fleet_against_single_runs(
    fleet_file: Path,
    started: dict[str, launch.Launched],
    keyword: str | None,
    out: Path,
    *extra: str,
    timing_may_be_inconclusive: bool = False,
) -> dict[str, Any]:
    """Run the fleet, then each target alone; assert the verdicts and exit statuses agree; the fleet's JSON.

    ``timing_may_be_inconclusive`` (the whole tier on a loaded machine): a case that judges what the platform did in
    time (flag timing or moves_platform) may be INCONCLUSIVE on one side - at time scale 10 a server that cannot
    keep up in one run and could in the other, which two single runs show as well - but a definite verdict (PASS,
    FAIL, NON-STRICT, N/A) must be the same on both sides, and every other case identical."""
    args = ["conform", "--targets", str(fleet_file), "--json", str(out / "fleet.json"), *extra]
    args += ["--junit", str(out / "junit"), "--html", str(out / "fleet.html")]
    code = main(args + (["-k", keyword] if keyword else []))
    report = json.loads((out / "fleet.json").read_text())
    fleet = {t["name"]: t for t in report["targets"]}
    assert list(fleet) == list(PROFILES)
    singles = {n: _single(t, PROFILES[n], keyword, out / f"{n}.json") for n, t in started.items()}
    timed = {c["id"] for c in fleet["reference"]["report"]["cases"] if {"timing", "moves_platform"} & set(c["flags"])}
    for name, (single_code, verdicts) in singles.items():
        got = {c["id"]: c["verdict"] for c in fleet[name]["report"]["cases"]}
        assert got.keys() == verdicts.keys(), name
        if timing_may_be_inconclusive:
            excused = {k for k in got if k in timed and "INCONCLUSIVE" in (got[k], verdicts[k])}
            got = {k: v for k, v in got.items() if k not in excused}
            verdicts = {k: v for k, v in verdicts.items() if k not in excused}
        assert got == verdicts, name
        if not timing_may_be_inconclusive:
            assert fleet[name]["exit_code"] == single_code, name
    if not timing_may_be_inconclusive:
        assert code == report["exit_code"] == max(c for c, _ in singles.values())
    for name in PROFILES:  # JUnit per target, each a whole single-run report
        root = ET.parse(out / "junit" / f"{name}.xml").getroot()
        assert root.get("name") == f"pltf conform {name}"
        assert sum(int(s.get("tests", "0")) for s in root) == len(fleet[name]["report"]["cases"])
    return report


def test_a_fleet_of_four_gives_each_target_its_single_run_verdicts_and_names_the_differences(
    four: tuple[Path, dict[str, launch.Launched]], tmp_path: Path
) -> None:
    fleet_file, started = four
    report = check_fleet_against_single_runs(fleet_file, started, FEW, tmp_path)
    rows = {r["case"]: r for r in report["matrix"]}
    assert len(rows) == 3
    framing = rows["6.2/framing/header-and-length"]
    assert not framing["differs"] and set(framing["verdicts"].values()) == {"PASS"}
    params = rows["5.9/parameters/errata-parameters"]
    assert params["differs"] and params["verdicts"] == {
        n: "N/A" if UPSTREAM.get(n, n) == "emulator" else "PASS" for n in PROFILES
    }
    (named,) = params["documented"]
    assert named.startswith("E-PAR-024 (errata register") and "zoo/emulator_differences.yaml" in named
    second = rows["6.1/ports/second-client-turned-away"]
    assert second["verdicts"]["emulator"] == "NON-STRICT" and any("E-WIRE-007" in d for d in second["documented"])
    html = (tmp_path / "fleet.html").read_text()
    assert html.count('class="r d"') == report["differences"] == 2
    assert "E-PAR-024" in html and "zoo/emulator_differences.yaml" in html


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_the_standard_tier_across_the_fleet_matches_single_runs(
    four: tuple[Path, dict[str, launch.Launched]], tmp_path: Path
) -> None:
    fleet_file, started = four
    report = check_fleet_against_single_runs(fleet_file, started, None, tmp_path, timing_may_be_inconclusive=True)
    assert len(report["matrix"]) > 150


# ---- what the command line refuses, in one line
def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("targets: []\n", "expected 'targets:'"),
        ("targets:\n- {name: a, target: 'h:1', colour: red}\n", "unknown key 'colour'"),
        ("targets:\n- {name: a, target: 'h:1'}\n- {name: a, target: 'h:2'}\n", "two targets are named 'a'"),
        ("targets:\n- {name: a, target: 'no-port'}\n", "target 1 (a): expected HOST:PORT"),
        ("targets:\n- {name: a, target: 'h:1', second_port: yes}\n", "second_port must be int"),
        ("targets:\n- {name: 'a/b', target: 'h:1'}\n", "a name is 1-64 letters"),
        ("targets:\n- {name: a, target: 'h:1', baseline: none.txt}\n", "baseline"),
        ("defaults: {name: x}\ntargets:\n- {name: a, target: 'h:1'}\n", "belongs to each target"),
        ("targets: [\n", "not YAML"),
    ],
)
def test_a_bad_fleet_file_is_one_line_and_exit_status_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, said: str
) -> None:
    path = tmp_path / "fleet.yaml"
    path.write_text(text, encoding="utf-8")
    assert main(["conform", "--targets", str(path), "-k", "6.2/framing/header-and-length"]) == 2
    err = capsys.readouterr().err
    assert said in err and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        (["--ray", "auto"], "--ray and --jobs run a fleet"),
        (["--targets", "F", "--baseline", "b.txt"], "not with --targets: --baseline"),
        (["--targets", "F", "--second-port", "2"], "--second-port belongs to each target"),
    ],
)
def test_options_that_do_not_fit_a_fleet_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], said: str
) -> None:
    (tmp_path / "F").write_text("targets:\n- {name: a, target: '127.0.0.1:1'}\n", encoding="utf-8")
    args = [a.replace("F", str(tmp_path / "F")) if a == "F" else a for a in extra]
    if "--targets" not in args:
        args = ["--target", "127.0.0.1:1", *args]
    assert main(["conform", *args]) == 2
    assert said in capsys.readouterr().err


def test_an_unreachable_target_is_named_and_the_others_are_reported(
    reference: launch.Launched, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "fleet.yaml"
    entries = [
        {"name": "ref", "target": f"127.0.0.1:{reference.ports[0]}", "second_port": reference.ports[1]},
        {"name": "gone", "target": f"127.0.0.1:{_closed_port()}"},
    ]
    path.write_text(yaml.safe_dump({"defaults": {"time_scale": 10, "target_is_simulator": True}, "targets": entries}))
    code = main(
        ["conform", "--targets", str(path), "-k", "6.2/framing/header-and-length", "--json", str(tmp_path / "r")]
    )
    assert code == 2
    err = capsys.readouterr().err
    assert "1 of 2 target(s) could not be checked: gone (" in err and "Traceback" not in err
    report = json.loads((tmp_path / "r").read_text())
    ref, gone = report["targets"]
    assert (ref["exit_code"], [c["verdict"] for c in ref["report"]["cases"]]) == (0, ["PASS"])
    assert gone["exit_code"] == 2 and gone["error"]


def test_ray_is_optional_and_its_absence_is_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import sys

    (tmp_path / "F").write_text(f"targets:\n- {{name: a, target: '127.0.0.1:{_closed_port()}'}}\n", encoding="utf-8")
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError: as without the extra
    args = ["conform", "--targets", str(tmp_path / "F"), "-k", "6.2/framing/header-and-length"]
    assert main(args) == 2  # without --ray the fleet runs (its one target is unreachable) and nothing imports ray
    assert "1 of 1 target(s) could not be checked: a (" in capsys.readouterr().err
    assert main([*args, "--ray", "auto"]) == 2
    err = capsys.readouterr().err
    assert "pip install 'pltf-toolkit[ray]'" in err and err.count("\n") == 1
