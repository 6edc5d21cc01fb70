"""examples/monitor.py against the reference server: the CSV has its header and one row per interval with the
status and the battery, and the monitor waits out a port another client holds (guide 6.1, erratum E-WIRE-007: the
second client is closed at once) and writes its rows once the port is free."""

from __future__ import annotations

import csv
import datetime
import itertools
import time
from pathlib import Path

from pltf.client import EmergencyState, MotionMode, OperationState, PlannerState, PlatformClient
from tests.clients.client_fakes import LiveServer
from tests.examples.runner import TIME_SCALE, Example, python_example, target

COLUMNS = [
    "time",
    "platform_ms",
    "state",
    "mode",
    "emergency",
    "x_mm",
    "y_mm",
    "angle_deg",
    "target_reached",
    "planner",
    "battery_mv",
]


def rows_of(path: Path) -> list[dict[str, str]]:
    with path.open(newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames == COLUMNS
        return list(reader)


def test_one_row_per_interval_with_status_and_battery(server: LiveServer, tmp_path: Path) -> None:
    with PlatformClient("127.0.0.1", server.ports[1], timeout=10) as watch:
        watch.bring_up(timeout=30)  # the IO board reports the battery once the CAN bus is up (before: 0)
    out = tmp_path / "status.csv"
    cmd = python_example(
        "monitor.py", "--target", target(server), "--count", "5", "--interval", "0.1", "--out", str(out)
    )
    with Example(cmd) as run:
        assert run.finish() == 0, run.stderr()
    rows = rows_of(out)
    assert len(rows) == 5
    stamps = [int(r["platform_ms"]) for r in rows]
    # 0.1 s apart on this computer: 0.5 s on the platform's clock at TIME_SCALE 5 (each less its scheduling jitter)
    assert all(a < b for a, b in itertools.pairwise(stamps)), stamps
    assert stamps[-1] - stamps[0] >= 0.5 * 4 * 0.1 * TIME_SCALE * 1000, stamps
    for r in rows:
        datetime.datetime.fromisoformat(r["time"])
        assert r["state"] in OperationState.__members__ and r["mode"] in MotionMode.__members__
        assert r["emergency"] in EmergencyState.__members__ and r["planner"] in PlannerState.__members__
        assert r["target_reached"] in ("0", "1")
        float(r["x_mm"]), float(r["y_mm"]), float(r["angle_deg"])
        assert 20000 <= int(r["battery_mv"]) <= 30000, r  # the fake IO board's 24 V battery
    with PlatformClient("127.0.0.1", server.ports[1], timeout=10) as watch:  # the last row is the platform now
        now = watch.get_status()
    assert rows[-1]["state"] == now.operation_state.name
    assert abs(float(rows[-1]["x_mm"]) - now.est_x_mm) < 50


def test_a_taken_port_is_waited_out(server: LiveServer, tmp_path: Path) -> None:
    out = tmp_path / "status.csv"
    cmd = python_example(
        "monitor.py",
        "--target",
        target(server),
        "--count",
        "3",
        "--interval",
        "0.05",
        "--retry",
        "0.2",
        "--out",
        str(out),
    )
    with PlatformClient("127.0.0.1", server.ports[0], timeout=10) as holder:  # the port's one client
        holder.get_status()
        run = Example(cmd)
        deadline = time.monotonic() + 20
        while "retrying" not in run.stderr() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert "retrying in 0.2 s" in run.stderr(), (run.stderr(), run.lines)
        assert rows_of(out) == []  # nothing but the header while the port is taken
    with run:
        assert run.finish() == 0, run.stderr()
    assert len(rows_of(out)) == 3


def test_an_unwritable_file_is_one_line(server: LiveServer, tmp_path: Path) -> None:
    cmd = python_example("monitor.py", "--target", target(server), "--out", str(tmp_path / "no" / "such.csv"))
    with Example(cmd) as run:
        assert run.finish() == 2
    assert run.stderr().startswith("monitor: error: ") and len(run.stderr().splitlines()) == 1
