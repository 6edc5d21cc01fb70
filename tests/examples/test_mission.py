"""examples/mission.py against the reference server: the map, roadmap and program arrive on the platform, the
program runs from this computer step by step in its order, and the platform ends where the program sends it."""

from __future__ import annotations

import math
import re
from pathlib import Path

from pltf.client import OperationState, PlatformClient
from tests.clients.client_fakes import LiveServer
from tests.examples.runner import EXAMPLES, REPO, TIME_SCALE, Example, python_example, target

STEP = re.compile(r"step (\d+\.\d\d) (\S+):(\d+) (\w+) (.*)$")
COMMANDS = [
    "settarget station Corridor_01",
    "settarget station Kitchen",
    "digitalout D1=1",
    "digitalout D1=0",
    "settarget coord x 5000 y 10000 a 180",
    "goto end",
]


def test_the_mission_loads_its_documents_and_reports_each_step(server: LiveServer) -> None:
    cmd = python_example("mission.py", "--target", target(server), "--time-scale", f"{TIME_SCALE:g}")
    with Example(cmd) as run:
        assert run.finish(timeout=120) == 0, (run.lines, run.stderr())
    sizes = [(REPO / p).stat().st_size for p in ("fixtures/maps/office.map", "fixtures/roadmaps/office.rm")]
    program = (EXAMPLES / "mission/mission.xml").stat().st_size
    assert run.lines[:3] == [
        f"loaded map office.map: {sizes[0]} bytes",
        f"loaded roadmap office.rm: {sizes[1]} bytes",
        f"loaded program mission.xml: {program} bytes",
    ]
    steps = [m.groups() for line in run.lines if (m := STEP.match(line))]
    assert [s[4] for s in steps if s[3] == "command"] == COMMANDS
    assert [float(s[0]) for s in steps] == sorted(float(s[0]) for s in steps)  # in the program's time order
    assert sum(1 for s in steps if s[4] == "wait over: target") == 3
    delay = [float(s[0]) for s in steps if "delay 2000 ms" in s[4]]
    assert delay[-1] - delay[0] >= 2.0  # <wait><delay amount="2000"/> on the program's (simulated) clock
    assert run.lines[-1] == "mission finished"
    with PlatformClient("127.0.0.1", server.ports[1], timeout=10) as watch:
        status = watch.get_status()
        assert math.hypot(status.est_x_mm - 5000, status.est_y_mm - 10000) <= 40
        assert abs((status.pose.angle_deg - 180 + 180) % 360 - 180) <= 3
        assert status.io_digital_out & 1 == 0  # D1 back off
        assert watch.get_program().xml == (EXAMPLES / "mission/mission.xml").read_bytes()


def test_a_mission_that_runs_out_of_time_fails_and_stops_the_platform(server: LiveServer) -> None:
    cmd = python_example("mission.py", "--target", target(server), "--time-scale", f"{TIME_SCALE:g}", "--timeout", "2")
    with Example(cmd) as run:
        assert run.finish(timeout=60) == 1, (run.lines, run.stderr())
    assert run.lines[-1] == "mission failed: still running after 2.0 s" or run.lines[-1].startswith("mission failed")
    with PlatformClient("127.0.0.1", server.ports[1], timeout=10) as watch:
        assert watch.get_status().operation_state is OperationState.ST_OP_READY


def test_an_invalid_program_is_one_line(server: LiveServer, tmp_path: Path) -> None:
    bad = tmp_path / "bad.xml"
    bad.write_text('<program version="1.0"><task name="t" id="1" priority="1"><nosuchthing/></task></program>')
    with Example(python_example("mission.py", "--target", target(server), "--program", str(bad))) as run:
        assert run.finish() == 2
    assert run.stderr().startswith("mission: error: ") and len(run.stderr().splitlines()) == 1, run.stderr()
