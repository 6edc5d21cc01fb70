"""The soak's last step (benchmarks/soak/replay.py): ``pltf replay`` of a soak-like recording against a fresh
reference server, with its peak RSS, duration and differences; and how the soak's report shows it.

The recording is the soak's parts without the browser, for a few seconds: the reference server at time scale 10,
``pltf proxy --record`` in front of it, a watcher polling CMD_GET_STATUS at 20 Hz on the first port (as the GUI
does), the patrol driving on the second and the reconnecting client turned away there every second.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from benchmarks.soak import integrity, report
from benchmarks.soak.parts import Plain, ProxyProcess
from benchmarks.soak.replay import Replayed, replay
from benchmarks.soak.run import Outcome, options
from pltf.harness.launch import REPO, python, reference

TIME_SCALE = 10.0
RECORD_S = 6.0


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    record = tmp_path_factory.mktemp("soak") / "session.jsonl"
    with reference(time_scale=TIME_SCALE, seed=1) as server:
        proxy = ProxyProcess(server.ports, record)
        try:
            l1, l2 = proxy.start()
            csv = str(record.with_suffix(".csv"))
            watcher = Plain([sys.executable, str(REPO / "examples" / "monitor.py"), "--target", f"127.0.0.1:{l1}",
                             "--interval", "0.05", "--out", csv], name="watcher")  # fmt: skip
            patrol = Plain([sys.executable, str(REPO / "examples" / "patrol.py"), "--target", f"127.0.0.1:{l2}",
                            "--rounds", "0"], name="patrol")  # fmt: skip
            reconnect = Plain(python("benchmarks.soak.reconnect", "--target", f"127.0.0.1:{l2}", "--every", "1"),
                              name="reconnecting client")  # fmt: skip
            with watcher, patrol:  # started on entering
                time.sleep(1.0)  # the patrol holds the second port before the first newcomer comes
                with reconnect:
                    time.sleep(RECORD_S)
        finally:
            proxy.stop_gently()
            proxy.cleanup()
    yield record


@pytest.mark.slow  # 30-40 s: the parts' start, 7 s of recording, the replay (measured at load 15-18)
@pytest.mark.timeout(300)
def test_a_soak_recording_replays_clean_against_a_fresh_server_with_its_peak_rss(recording: Path) -> None:
    check = integrity.check(recording)
    assert check.clean, check.problems
    assert len(check.connections) == 2 and check.frames > 100  # both ports, the watcher's 20 Hz polling
    r = replay(recording, TIME_SCALE)
    assert r.status == 0, "\n".join(r.lines)
    assert r.differences == 0 and r.lines[-1].endswith(": no difference")
    assert 10 < r.peak_rss_mb < 500  # the replay process's own high-water mark, not the harness's
    assert RECORD_S / 2 < r.seconds < 120  # it replays at the recorded pace


def test_a_replay_that_found_differences_fails_the_soak_and_its_lines_are_in_the_report(tmp_path: Path) -> None:
    lines = [
        "replayed 30 of 30 requests on 3 connections (20 replies compared, 1 waits):",
        "CMD_GET_STATUS: 1 difference",
        "  #1 :10000    1.000 s  CMD_GET_STATUS",
        "      app_error: recorded 0, replayed 2",
        "1 difference in 1 telegram(s)",
    ]
    r = Replayed(1, 123.4, 56.7, lines)
    assert r.differences == 1 and r.summary() == "exit status 1, 1 difference, 57 s, peak RSS 123.4 MB"
    assert Replayed(0, 1.0, 1.0, ["replayed 3 of 3 requests ...: no difference"]).differences == 0
    assert Replayed(None, 1.0, 1.0, []).summary().startswith("did not end in time, no count printed")
    args = options(["--minutes", "0.5", "--interval", "10", "--warmup", "10"])
    assert args.duration == 30.0 and args.replay
    sample = {"t": 30.0, "load": 1.0, "procs": {}, "recording": {"bytes": 10, "telegrams": 1}, "dead": []}
    outcome = Outcome([sample], [], replayed=r, reconnect="reconnect: 9 connections: ConnectionClosed=9")
    outcome.recording_check = integrity.Integrity()
    text = report.render(args, outcome, tmp_path)
    assert "FAILED" in text.splitlines()[0] and not report.passed(args, outcome)
    assert "exit status 1, 1 difference, 57 s, peak RSS 123.4 MB" in text
    assert "app_error: recorded 0, replayed 2" in text


def test_the_soak_s_options(capsys: pytest.CaptureFixture[str]) -> None:
    assert not options(["--no-replay"]).replay
    with pytest.raises(SystemExit):
        options(["--minutes", "0"])
    assert "must be positive" in capsys.readouterr().err
