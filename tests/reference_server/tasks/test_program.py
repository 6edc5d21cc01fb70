"""Programs on the platform (MODE_MOTION_PROGRAM) over the socket API: refusal of invalid programs, CMD_START /
CMD_BREAK / CMD_CONTINUE / CMD_STOP, priorities, user events, and local versus remote mode."""

from __future__ import annotations

import logging
import re
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from pltf.client import OperationState
from pltf.reference_server.tasks.program import load_program
from pltf.spec.documents import DocumentError
from tests.reference_server.tasks.conftest import SCALE, Session, program, program_server, task
from tests.reference_server.tasks.test_waits import at

PATROL = program(
    task(
        "<parameter><set key='IpoTransVel' value='900'/></parameter>"
        "<motion><settarget><station name='Kitchen'/></settarget></motion><wait timeout='90000'><target/></wait>"
        "<wait><random min='500' max='1500'/></wait>"
        "<motion><settarget><coord x='7000' y='10000' angle='-90'/></settarget></motion>"
        "<wait timeout='90000'><target/></wait><wait><delay amount='800'/></wait>"
        "<motion><settarget><station name='Server'/></settarget></motion><wait timeout='90000'><target/></wait>"
        "<wait><delay amount='800'/></wait>"
        "<motion><settarget><station name='Corridor_01'/></settarget></motion><wait timeout='90000'><target/></wait>"
        "<wait><delay amount='800'/></wait>"
    )
)


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        ("<ioevent><digitalout D1='2'/></ioevent>", None),  # the schema's message
        ("<goto label='nowhere'/>", "no label 'nowhere' in this task"),
    ],
)
def test_an_invalid_program_is_refused_and_the_active_one_stays(session: Session, body: str, expected: str) -> None:
    before = session.client.get_program().xml
    bad = program(task(body))
    if expected is None:
        with pytest.raises(DocumentError) as info:
            load_program(bad.encode())
        expected = info.value.reason
    session.client.set_program(bad)
    session.wait_log("refused")
    assert any(expected in line for line in session.log()), session.lines[-4:]
    assert session.client.get_program().xml == before
    lines = session.run_local(program(task("<log message='still the good one'/>")))
    assert any("still the good one" in line for line in lines)


def test_break_freezes_the_program_and_continue_resumes_it(session: Session) -> None:
    # 20 s of platform time between A and B (1 s of wall time at the time scale of 20): the BREAK must land in it
    session.run_local(
        program(task("<log message='A'/><wait><delay amount='20000'/></wait><log message='B'/>")), wait_finished=False
    )
    session.wait_log("] A")
    # The protocol does not say when the platform acted on a command, only when it answered a status: the pause
    # the program saw lies between the last status before BREAK and the first after CONTINUE (longest) and the
    # first status in Break and the last one before CONTINUE (shortest). A loaded machine widens the bracket.
    before_break = session.status().timestamp_ms
    session.client.break_()
    session.client.wait_state(OperationState.ST_OP_BREAKED)
    in_break = session.status().timestamp_ms
    while (before_continue := session.status().timestamp_ms) - in_break < 2000:  # 2 s of the platform's time
        time.sleep(0.2 / SCALE)
    session.client.continue_()
    after_continue = session.status().timestamp_ms
    lines = session.wait_log("program finished")
    shortest, longest = (before_continue - in_break) / 1000.0, (after_continue - before_break) / 1000.0
    assert 20.0 + shortest - 0.2 <= at(lines, "B") - at(lines, "A") <= 20.0 + longest + 0.2


def test_stop_aborts_the_program(session: Session) -> None:
    session.run_local(
        program(
            task(
                "<motion><settarget><coord x='20000' y='10000'/></settarget></motion>"
                "<wait><delay amount='5000'/></wait><log message='never'/>"
            )
        ),
        wait_finished=False,
    )
    time.sleep(1.0 / SCALE)
    session.client.stop()
    session.wait_log("program stopped")
    st = session.client.wait_state(OperationState.ST_OP_READY)
    x, v = st.est_x_mm, abs(st.vel_trans_mm_s)
    time.sleep(6.0 / SCALE)
    # CMD_STOP brakes with MaxTransAcc (800 mm/s^2, E-MOT-005): from its speed when READY the platform stops within
    # v^2 / 1600 mm (a fixed 600 mm failed whenever the first plan came quickly enough for ~1 m/s at the stop); a
    # program that drove on towards x = 20000 would go metres further
    assert not session.saw("never") and session.status().vel_trans_mm_s == 0
    assert session.status().est_x_mm - x < v * v / (2 * 800.0) + 100.0, (x, v, session.status().est_x_mm)


def test_priorities_order_the_tasks_and_handlers_wait_for_their_call(session: Session) -> None:
    lines = session.run_local(
        program(
            task("<log message='low'/>", "low", 1),
            task("<log message='high'/>", "high", 7),
            task("<log message='handler'/>", "handler", 9),
            task("<motion><moveto onErrorTask='handler'><trackedball/></moveto></motion>", "caller", 0),
        )
    )
    order = [line.rsplit("] ", 1)[1] for line in lines if "task log [info]" in line and "] task " not in line]
    assert order == ["high", "low", "handler"]


def test_a_user_event_releases_the_waiting_task(session: Session) -> None:
    session.run_local(
        program(
            task(
                "<log message='A'/><wait timeout='60000' timeoutlabel='late'><userevent id='door_open'/></wait>"
                "<log message='B'/><label name='late'/>"
            )
        ),
        wait_finished=False,
    )
    session.wait_log("] A")
    released = session.server.call(session.server.platform.program.raise_event, "door_open")
    lines = session.wait_log("program finished")
    assert released == 1
    assert at(lines, "B") - at(lines, "A") < 10.0


REACHED = re.compile(r"target reached: x (-?\d+) mm, y (-?\d+) mm")


class _Reached(logging.Handler):
    """Every target the platform reports reached, in order: its "target reached" lines of the server's log (the
    "pltf.server" logger; the protocol queue of CMD_GET_DEBUG_DATA keeps 32 lines, and a poller starved on a loaded
    machine lost one)."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.seen: list[tuple[int, int]] = []

    def emit(self, record: logging.LogRecord) -> None:
        if m := REACHED.search(record.getMessage()):
            self.seen.append((int(m[1]), int(m[2])))


def _watched(run: Callable[[], object]) -> list[tuple[int, int]]:
    logger, reached = logging.getLogger("pltf.server"), _Reached()
    level = logger.level
    logger.addHandler(reached)
    logger.setLevel(logging.INFO)
    try:
        run()
    finally:
        logger.removeHandler(reached)
        logger.setLevel(level)
    return reached.seen


def test_the_same_program_locally_and_remotely_reaches_the_same_targets_in_order(tmp_path: Path) -> None:
    runs = {}
    for mode in ("local", "remote"):
        srv = program_server(tmp_path / mode)
        try:
            with Session(srv) as s:
                if mode == "local":
                    runs[mode] = _watched(lambda s=s: s.run_local(PATROL, timeout=60))
                else:
                    runs[mode] = _watched(lambda s=s: s.run_remote(PATROL, tmp_path, seed=1))
        finally:
            srv.stop()
    local, remote = runs["local"], runs["remote"]
    assert len(local) == 4, local
    assert len(remote) == len(local), (local, remote)
    for (lx, ly), (rx, ry) in zip(local, remote, strict=True):
        assert abs(lx - rx) <= 60 and abs(ly - ry) <= 60, (local, remote)
