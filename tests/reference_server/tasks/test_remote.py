"""Remote mode (guide 4.5): the program runs in the test process and drives the server by socket commands only."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from pltf.client import MotionMode, OperationState
from tests.reference_server.conftest import ServerThread
from tests.reference_server.helpers import REPO
from tests.reference_server.tasks.conftest import SCALE, Session, program, task

# The waits for a target are bounded at 600 s: a remote program's clock is this computer's (E-TASK-014), which runs
# on while a loaded server holds its simulated time (a clean-clone run at load 10: 55 s held in all, and a 60 s
# wait ended with the platform short of the station)


def test_remote_run_moves_sets_outputs_and_parameters(session: Session, tmp_path: Path) -> None:
    xml = program(
        task(
            "<ioevent><digitalout D1='1' D3='1' D12='1'/></ioevent>"
            "<parameter><set key='IpoTransVel' value='450'/></parameter>"
            "<motion><settarget><coord x='3500' y='10000' angle='90'/></settarget></motion>"
            "<wait timeout='600000'><target/></wait>"
            "<ioevent><digitalout D3='0'/></ioevent>"
            "<motion><settarget><station name='Kitchen'/></settarget></motion>"
            "<wait timeout='600000'><target/></wait>"
        )
    )
    result = session.run_remote(xml, tmp_path)
    assert result.finished and not result.failed
    st = session.status()
    assert abs(st.est_x_mm - 5000) < 60 and abs(st.est_y_mm - 12200) < 60, (st.est_x_mm, st.est_y_mm, result)
    assert st.motion_mode == MotionMode.MODE_MOTION_AUTOMATIC and st.operation_state == OperationState.ST_OP_RUNNING
    assert session.client.get_pltf_param("IpoTransVel").value == "450"


def test_remote_load_sends_the_local_files_and_grab_writes_locally(session: Session, tmp_path: Path) -> None:
    (tmp_path / "Roadmap").mkdir()
    rm = (REPO / "fixtures" / "roadmaps" / "office.rm").read_bytes().replace(b'name="Kitchen"', b'name="Pantry"')
    (tmp_path / "Roadmap" / "other.rm").write_bytes(rm)
    (tmp_path / "office.map").write_bytes((REPO / "fixtures" / "maps" / "office.map").read_bytes())
    xml = program(
        task(
            "<load map='office.map' roadmap='other.rm'/>"
            "<motion><settarget><station name='Pantry'/></settarget></motion><wait timeout='600000'><target/></wait>"
            "<surveillance><grab filename='shot' grabscan='true' grabimage='true'/></surveillance>"
        )
    )
    result = session.run_remote(xml, tmp_path)
    assert result.finished and not result.failed
    assert session.client.get_roadmap().name == "other.rm" and session.client.get_map().name == "office.map"
    st = session.status()
    assert abs(st.est_x_mm - 5000) < 60 and abs(st.est_y_mm - 12200) < 60
    assert (tmp_path / "shot.dat").read_text().startswith("# pltf scan grab")
    assert (tmp_path / "shot.jpg").read_bytes()[:2] == b"\xff\xd8"


def test_remote_missing_file_fails_the_task(session: Session, tmp_path: Path) -> None:
    result = session.run_remote(program(task("<load map='nothere.map'/><log message='never'/>")), tmp_path)
    assert result.failed == ["main"]
    assert any("nothere.map" in r.text for r in result.records)


def test_pltf_run_program_plain_and_invalid(server: ServerThread, tmp_path: Path) -> None:
    good = tmp_path / "good.xml"
    good.write_text(program(task("<log message='hello from afar'/><wait><delay amount='200'/></wait>")))
    target = f"127.0.0.1:{server.ports[1]}"
    cmd = [sys.executable, "-m", "pltf.cli.main", "run-program", "--target", target, "--time-scale", str(SCALE)]
    done = subprocess.run(
        [*cmd, "--plain", str(good)], check=False, capture_output=True, text=True, timeout=60, cwd=REPO
    )
    assert done.returncode == 0, done.stderr
    assert "hello from afar" in done.stdout and "program finished" in done.stdout
    bad = tmp_path / "bad.xml"
    bad.write_text(program(task("<ioevent><digitalout D1='2'/></ioevent>")))
    refused = subprocess.run([*cmd, str(bad)], check=False, capture_output=True, text=True, timeout=60, cwd=REPO)
    assert refused.returncode == 2
    assert "D1" in refused.stderr and "line 1" in refused.stderr
