"""The hardware cases (CAN traffic, IO outputs, ultrasonic board, head drive, task interpreter) on a second target,
independent of the reference server (which passes them with its fake hardware, test_reference.py): they pass on a
small fake that has that hardware, and fail when it is broken."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from pltf.conformance_tests.catalogue import Level, Verdict, load_all
from pltf.conformance_tests.runner import CaseResult, Runner
from pltf.conformance_tests.target import Config
from tests.conformance_tests.fakes import HardwareTarget

FAULTS = {
    "6.3/CMD_GET_CAN_MESSAGES/keep-and-delete": "can-keep-deletes",
    "6.3/CMD_REMOVE_CAN_LISTENING_ID/stops-buffering": "can-ignores-remove",
    "6.3/CMD_GET_CAN_MESSAGES/listened-ids-only": "can-all-ids",
    "6.4/CMD_GET_CAN_MESSAGES/timestamps": "can-time-backwards",
    "6.3/CMD_SET_DIGOUT/sets-output": "digout-off-by-one",
    "6.3/CMD_SET_POS_HEAD_DRIVE/turns-head": "head-off",
    "6.3/CMD_START_ULTRASONIC/measures": "us-none",
    "4.5/program/runs-on-start": "program-ignores-delay",
    "4.5/program/stop-aborts": "program-ignores-stop",
    "4.5/program/break-pauses": "program-ignores-break",
}


def run(case_id: str, broken: frozenset[str] = frozenset()) -> CaseResult:
    with HardwareTarget(broken) as target:
        config = Config(
            "127.0.0.1",
            target.ports[0],
            target.ports[1],
            time_scale=10.0,
            simulator=True,
            reruns=0,
            reply_timeout=1.0,
            connect_window=1.0,
        )
        (result,) = Runner(config, [load_all()[case_id]]).run().results
        return result


@pytest.fixture(params=sorted(FAULTS))
def case_id(request: pytest.FixtureRequest) -> Iterator[str]:
    yield request.param


def test_passes_with_the_hardware(case_id: str) -> None:
    r = run(case_id)
    assert r.verdict is Verdict.PASS, f"{r.verdict}: {r.message}"


def test_fails_when_the_hardware_is_broken(case_id: str) -> None:
    r = run(case_id, frozenset({FAULTS[case_id]}))
    case = load_all()[case_id]
    if case.level is Level.MAY:  # a MAY requirement fails as N/A; the message tells it from absent hardware
        assert r.verdict is Verdict.NA, r.message
    else:
        assert r.verdict in (Verdict.FAIL, Verdict.NON_STRICT), f"{r.verdict}: {r.message}"
