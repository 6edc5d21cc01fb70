"""``pltf conform``: arguments, exit status 0/1/2, reports and baseline from the command line."""

from __future__ import annotations

import json
import socket
from pathlib import Path

import pytest

from pltf.cli.main import main
from pltf.harness import launch
from tests.conformance_tests.fakes import ScriptedServer


def _args(server: launch.Launched, *extra: str) -> list[str]:
    return [
        "conform",
        "--target",
        f"127.0.0.1:{server.ports[0]}",
        "--second-port",
        str(server.ports[1]),
        "--time-scale",
        "10",
        "--target-is-simulator",
        *extra,
    ]


def test_passing_selection_exits_0_and_writes_reports(
    reference: launch.Launched, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        _args(
            reference,
            "-k",
            "6.3/CMD_SET_MODE/* or 6.2/framing/coalesced",
            "--json",
            str(tmp_path / "r.json"),
            "--junit",
            str(tmp_path / "r.xml"),
            "--html",
            str(tmp_path / "r.html"),
        )
    )
    assert code == 0
    out = capsys.readouterr().out
    assert "Results by guide section" in out and "exit status 0" in out
    data = json.loads((tmp_path / "r.json").read_text())
    assert len(data["cases"]) == 10 and all(c["verdict"] == "PASS" for c in data["cases"])
    assert (tmp_path / "r.xml").exists() and (tmp_path / "r.html").exists()


def test_a_stale_baseline_entry_exits_1(reference: launch.Launched, tmp_path: Path) -> None:
    base = tmp_path / "known.txt"
    base.write_text("6.3/CMD_SET_MODE/in-running FAIL  # claimed broken, but it passes\n")
    assert main(_args(reference, "-k", "6.3/CMD_SET_MODE/in-running", "--baseline", str(base))) == 1


def test_coverage_below_the_threshold_exits_1(reference: launch.Launched) -> None:
    assert main(_args(reference, "-k", "6.1/ports/reconnect", "--coverage-threshold", "100")) == 1
    assert main(_args(reference, "-k", "6.1/ports/reconnect", "--coverage-threshold", "0")) == 0


def test_a_failing_case_exits_1(tmp_path: Path) -> None:
    with launch.reference(time_scale=10.0, mutant="set_mode_anywhere") as broken:
        assert (
            main(_args(broken, "-k", "6.3/CMD_SET_MODE/in-running", "--write-baseline", str(tmp_path / "b.txt"))) == 1
        )
    assert "6.3/CMD_SET_MODE/in-running  FAIL" in (tmp_path / "b.txt").read_text()


def test_harness_errors_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    assert main(["conform", "--target", f"127.0.0.1:{port}"]) == 2
    assert "harness error" in capsys.readouterr().out
    with pytest.raises(SystemExit) as exc:
        main(["conform", "--target", "no-port-here"])
    assert exc.value.code == 2
    assert main(["conform", "--target", f"127.0.0.1:{port}", "-k", "no-such-case-anywhere"]) == 2
    assert main(["conform", "--target", f"127.0.0.1:{port}", "-k", "and or"]) == 2


def test_list(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["conform", "--target", "h:1", "--list", "--tier", "smoke"]) == 0
    out = capsys.readouterr().out
    assert "6.2/framing/header-and-length" in out and "cases" in out


def test_differential_and_stateful_from_the_command_line(
    reference: launch.Launched, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(
        _args(
            reference,
            "-k",
            "6.1/ports/reconnect",
            "--differential",
            "--stateful",
            "5",
            "--stateful-out",
            str(tmp_path / "st"),
        )
    )
    out = capsys.readouterr().out
    assert code == 0, out
    assert "differential: the target answered like the reference server" in out
    assert "stateful test: 5 examples" in out


def test_a_target_that_hangs_up_during_the_differential_run_fails_it_without_a_traceback(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with ScriptedServer(lambda conn: None, ports=2) as target:  # accepts, then closes every connection
        code = main(
            [
                "conform",
                "--target",
                f"127.0.0.1:{target.ports[0]}",
                "--second-port",
                str(target.ports[1]),
                "--time-scale",
                "10",
                "-k",
                "6.1/ports/reconnect",
                "--differential",
            ]
        )
    out = capsys.readouterr()
    assert code == 1
    assert "differential run aborted: FAIL" in out.out
    assert "Traceback" not in out.out + out.err
