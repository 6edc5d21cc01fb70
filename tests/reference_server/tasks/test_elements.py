"""Every element of guide 6.5 Task, run locally (MODE_MOTION_PROGRAM) and observed over the socket API only:
position, parameters, outputs, status, documents, the protocol queue and the data dir."""

from __future__ import annotations

from pathlib import Path

from pltf.client import OperationState
from pltf.reference_server.status import ABSENT
from tests.reference_server.helpers import REPO
from tests.reference_server.tasks.conftest import Session, program, task

TOL = 60  # mm


def near(session: Session, x: int, y: int, tol: int = TOL) -> bool:
    st = session.status()
    return abs(st.est_x_mm - x) <= tol and abs(st.est_y_mm - y) <= tol


def test_ioevent_digitalout_sets_io_board_outputs_and_minus_one_keeps_them(session: Session) -> None:
    assert session.status().io_status != ABSENT, "the task fixtures run the fake hardware: the IO board answers"
    session.run_local(
        program(
            task(
                "<ioevent><digitalout D1='1' D3='1' D12='1'/></ioevent>"
                "<wait><delay amount='200'/></wait>"
                "<ioevent><digitalout D1='0' D2='-1' D3='-1' D12='0' D5='1'/></ioevent>"
                "<wait><delay amount='200'/></wait>"
            )
        )
    )
    out = session.wait_status(lambda s: s.io_digital_out == 0b10100, what="outputs D3 and D5 on").io_digital_out
    assert out == 0b10100


def test_ioevent_digitalout_sends_one_set_digout_per_changed_output(session: Session) -> None:
    lines = session.run_local(program(task("<ioevent><digitalout D2='1' D4='-1' D7='0'/></ioevent>")))
    sent = [line for line in lines if "CMD_SET_DIGOUT" in line or "digital out" in line.lower()]
    assert len(sent) == 2, lines


def test_goto_jumps_when_its_condition_holds(session: Session) -> None:
    session.run_local(
        program(
            task(
                "<goto label='a' condition='param:IpoTransVel!=12345'/>"
                "<parameter><set key='FlashlightEnabled' value='true'/></parameter>"
                "<label name='a'/><goto label='b' condition='false'/>"
                "<parameter><set key='IpoTransVel' value='321'/></parameter>"
                "<label name='b'/><goto label='c'/><parameter><set key='IpoTransVel' value='999'/></parameter>"
                "<label name='c'/>"
            )
        )
    )
    assert session.client.get_pltf_param("IpoTransVel").value == "321"
    assert session.client.get_pltf_param("FlashlightEnabled").value == "false"


def test_label_is_the_target_of_a_backward_goto_and_of_a_timeoutlabel(session: Session) -> None:
    lines = session.run_local(
        program(
            task(
                "<label name='top'/><goto label='second' condition='param:FlashlightEnabled==true'/>"
                "<parameter><set key='FlashlightEnabled' value='true'/></parameter><log message='first pass'/>"
                "<goto label='top'/><label name='second'/><log message='second pass'/>"
                "<wait timeout='100' timeoutlabel='late'><userevent id='never'/></wait>"
                "<parameter><set key='IpoTransVel' value='111'/></parameter>"
                "<label name='late'/><log message='label reached'/>"
            )
        )
    )
    logged = [line.rsplit("] ", 1)[1] for line in lines if "task log [info]" in line and "] task " not in line]
    assert logged == ["first pass", "second pass", "label reached"]
    assert session.client.get_pltf_param("IpoTransVel").value != "111"


def test_load_activates_the_named_map_and_roadmap_of_the_data_dir(session: Session) -> None:
    data = Path(session.server.platform.storage.root)
    rm = (REPO / "fixtures" / "roadmaps" / "office.rm").read_bytes().replace(b'name="Kitchen"', b'name="Pantry"')
    (data / "Roadmap" / "other.rm").write_bytes(rm)
    (data / "Map" / "other.map").write_bytes((REPO / "fixtures" / "maps" / "office.map").read_bytes())
    session.run_local(
        program(
            task(
                "<load map='other.map' roadmap='other.rm'/>"
                "<motion><settarget><station name='Pantry'/></settarget></motion><wait timeout='60000'><target/></wait>"
            )
        )
    )
    assert session.client.get_map().name == "other.map" and session.client.get_roadmap().name == "other.rm"
    assert near(session, 5000, 12200)


def test_load_of_a_missing_file_fails_the_task_and_keeps_the_documents(session: Session) -> None:
    lines = session.run_local(program(task("<load roadmap='ghost.rm'/><log message='never'/>")))
    assert session.client.get_roadmap().name == "PltfRoadmap.rm"
    assert any("ghost.rm" in line for line in lines) and not any("never" in line for line in lines)


def test_log_goes_to_the_protocol_queue_with_its_type(session: Session) -> None:
    lines = session.run_local(program(task("<log type='warning' message='battery low, going home'/>")))
    assert any("task log [warning] battery low, going home" in line for line in lines)


def test_motion_settarget_coord_reaches_the_frame(session: Session) -> None:
    session.run_local(
        program(
            task(
                "<motion><settarget><coord x='3500' y='10500' angle='90'/></settarget></motion>"
                "<wait timeout='60000'><target/></wait>"
            )
        )
    )
    st = session.status()
    assert near(session, 3500, 10500) and abs(st.est_angle_mdeg - 90000) < 2000 and st.target_reached


def test_motion_settarget_station_drives_over_the_roadmap(session: Session) -> None:
    session.run_local(
        program(
            task("<motion><settarget><station name='Lab'/></settarget></motion><wait timeout='60000'><target/></wait>")
        )
    )
    assert near(session, 7000, 7800)


def test_motion_stop_ends_the_move_short_of_its_target(session: Session) -> None:
    session.run_local(
        program(
            task(
                "<motion><settarget><coord x='20000' y='10000'/></settarget></motion>"
                "<wait><delay amount='1500'/></wait><motion stop='1'/><wait><delay amount='3000'/></wait>"
            )
        )
    )
    st = session.status()
    assert st.vel_trans_mm_s == 0 and not st.target_reached and 2100 < st.est_x_mm < 10000
    assert st.operation_state == OperationState.ST_OP_RUNNING


def test_moveto_charging_station_docks_at_its_frame(session: Session) -> None:
    session.run_local(
        program(
            task(
                "<parameter><set key='IpoTransVel' value='1000'/></parameter>"
                "<motion><moveto onErrorTask='none'><chargingstation/></moveto></motion>"
                "<wait timeout='120000'><target/></wait>",
                "main",
            ),
            task("<log message='no station'/>", "none"),
        ),
        timeout=30,
    )
    assert near(session, 31200, 10000) and not session.saw("no station")


def test_moveto_without_an_entity_runs_on_error_task_then_goes_on(session: Session) -> None:
    lines = session.run_local(
        program(
            task(
                "<motion><moveto onErrorTask='recover'><trackedperson/></moveto></motion>"
                "<parameter><set key='SirenEnabled' value='true'/></parameter>"
            ),
            task("<parameter><set key='IpoTransVel' value='222'/></parameter>", "recover", 3),
        )
    )
    assert session.client.get_pltf_param("IpoTransVel").value == "222"
    assert session.client.get_pltf_param("SirenEnabled").value == "true"
    assert near(session, 2000, 10000)  # the platform did not move
    assert any("onErrorTask recover" in line for line in lines)


def test_parameter_set_changes_the_platform_parameter(session: Session) -> None:
    session.run_local(program(task("<parameter><set key='SirenEnabled' value='true'/></parameter>")))
    assert session.client.get_pltf_param("SirenEnabled").value == "true"
    assert session.status().siren


def test_surveillance_grab_writes_scan_and_image_into_the_data_dir(session: Session) -> None:
    data = Path(session.server.platform.storage.root)
    session.run_local(
        program(
            task(
                "<surveillance><grab filename='round1' grabscan='true' grabimage='true' autoobservation='true'/>"
                "</surveillance>"
                "<surveillance><grab filename='scanonly' grabscan='true'/></surveillance>"
            )
        )
    )
    assert (data / "round1.dat").read_text().startswith("# pltf scan grab")
    assert (data / "round1.jpg").read_bytes()[:3] == b"\xff\xd8\xff"
    assert (data / "scanonly.dat").exists() and not (data / "scanonly.jpg").exists()
    assert session.client.get_pltf_param("SurveillanceModeEnabled").value == "true"


def test_surveillance_movecamera_reaches_the_camera_command(session: Session) -> None:
    lines = session.run_local(program(task("<surveillance><movecamera position='pan=30 tilt=-10'/></surveillance>")))
    assert any("CMD_SET_POS_PAN_TILT_CAMERA" in line for line in lines)


def test_audio_speak_and_play_are_recorded_with_text_and_file(session: Session) -> None:
    lines = session.run_local(
        program(task("<audio><speak text='Welcome to the lab'/></audio><audio><play filename='chime.wav'/></audio>"))
    )
    assert any("Welcome to the lab" in line for line in lines)
    assert any("chime.wav" in line for line in lines)


def test_turnhead_moves_the_head_drive_shown_in_the_status(session: Session) -> None:
    session.run_local(program(task("<turnhead angle='-45'/>")))
    assert session.wait_status(lambda s: s.head_position_deg == -45, what="head at -45 deg").head_position_deg == -45
