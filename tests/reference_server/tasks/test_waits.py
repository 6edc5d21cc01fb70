"""Every <wait> condition of guide 6.5, run locally and timed by the protocol queue over the socket API.

The queue's lines start with the simulated time (E-SRV-017), so "A" ... wait ... "B" measures the wait to the
control period (20 ms). Sensors the simulation cannot trigger from outside yet (collision, detections, lost
localization, IR, radar) are checked on their quiet side here: the wait reads the status telegram, finds
nothing and ends by its timeout, at its label; test_interpreter.py checks their release at the facade.
"""

from __future__ import annotations

import pytest

from tests.reference_server.tasks.conftest import Session, program, task

PERIOD = 0.02


def at(lines: list[str], text: str) -> float:
    for line in lines:
        stamp, _, rest = line.partition(" ")
        if rest.endswith(f"] {text}"):
            return float(stamp)
    raise AssertionError(f"no log line ending with {text!r}")


def between(session: Session, body: str, **run: float) -> float:
    lines = session.run_local(program(task(f"<log message='A'/>{body}<log message='B'/>")), **run)
    return at(lines, "B") - at(lines, "A")


def test_delay_waits_its_milliseconds(session: Session) -> None:
    assert between(session, "<wait><delay amount='2000'/></wait>") == pytest.approx(2.0, abs=PERIOD + 1e-6)


def test_random_waits_within_min_max_and_the_same_with_the_same_seed(session: Session) -> None:
    body = "<wait><random min='500' max='3000'/></wait>"
    first = between(session, body)
    session.lines.clear()
    second = between(session, body)
    assert 0.5 - PERIOD <= first <= 3.0 + PERIOD
    assert second == pytest.approx(first, abs=PERIOD + 1e-6)  # CMD_START reseeds (E-TASK-009)


def test_date_waits_for_the_platforms_local_time(session: Session) -> None:
    now = session.status().timestamp_ms / 1000.0  # simulated s since start; local time = 2030-01-01 + now
    # 30 simulated s ahead (0.6 s of wall time): 4 s ahead (80 ms) had passed before the program ran on a loaded
    # machine (a clean-clone run at load 9: 'B' at 5.2 s for a wait until 5 s)
    when = int(now) + 30
    assert when < 3600
    lines = session.run_local(
        program(
            task(
                f"<wait><date year='2030' month='1' day='1' hour='0' minute='{when // 60}' "
                f"second='{when % 60}'/></wait><log message='B'/>"
            )
        )
    )
    assert at(lines, "B") == pytest.approx(when, abs=PERIOD + 1e-6)


def test_target_waits_until_the_platform_stands_at_its_target(session: Session) -> None:
    lines = session.run_local(
        program(
            task(
                "<motion><settarget><coord x='4000' y='10000'/></settarget></motion><log message='A'/>"
                "<wait timeout='60000' timeoutlabel='late'><target/></wait><log message='B'/><label name='late'/>"
            )
        )
    )
    assert at(lines, "B") - at(lines, "A") > 1.0
    st = session.status()
    assert st.target_reached and abs(st.est_x_mm - 4000) < 60


def test_timeout_goes_to_timeoutlabel_or_on(session: Session) -> None:
    lines = session.run_local(
        program(
            task(
                "<log message='A'/><wait timeout='700' timeoutlabel='t'>"
                "<userevent id='x'/></wait><log message='skipped'/>"
                "<label name='t'/><log message='B'/><wait timeout='300'/><log message='C'/>"
            )
        )
    )
    assert at(lines, "B") - at(lines, "A") == pytest.approx(0.7, abs=PERIOD + 1e-6)
    assert at(lines, "C") - at(lines, "B") == pytest.approx(0.3, abs=PERIOD + 1e-6)
    assert not any(line.endswith("skipped") for line in lines)


@pytest.mark.parametrize(
    "element",
    [
        "<collision/>",
        "<movingobject/>",
        "<movingobjects/>",
        "<person/>",
        "<ball/>",
        "<lostlocalization/>",
        "<lostlocalisation/>",
        "<infrared direction='front'/>",
        "<radar direction='any'/>",
        "<batterycharge limit='101'/>",
    ],
)
def test_sensor_waits_read_the_status_and_time_out_when_nothing_happens(session: Session, element: str) -> None:
    assert between(session, f"<wait timeout='400'>{element}</wait>") == pytest.approx(0.4, abs=PERIOD + 1e-6)


def test_batterycharge_ends_when_the_charge_is_at_the_limit(session: Session) -> None:
    lines = session.run_local(
        program(
            task(
                "<log message='A'/><wait timeout='2000' timeoutlabel='t'>"
                "<batterycharge limit='0'/></wait><log message='B'/>"
                "<label name='t'/>"
            )
        )
    )
    assert at(lines, "B") == at(lines, "A")
