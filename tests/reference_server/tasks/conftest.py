"""Fixtures of the task interpreter's socket tests: a reference server at an accelerated time scale, a client,
and helpers that run a program locally (MODE_MOTION_PROGRAM) or remotely (pltf run-program's loop)."""

from __future__ import annotations

import datetime
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from pltf.cli.run_program_cmd import RunResult, prepare, run_remote
from pltf.client import MotionMode, OperationState, PlatformClient, Status
from pltf.reference_server import hardware_link
from pltf.reference_server.tasks.local import factory
from pltf.reference_server.tasks.program import load_program
from pltf.reference_server.tasks.remote import RemoteMachine
from tests.reference_server.conftest import ServerThread

SCALE = 50.0  # simulated seconds per wall second
EPOCH = datetime.datetime(2030, 1, 1)  # the reference server's (E-TASK-010)
FINISHED = "program finished"


def program(*tasks: str) -> str:
    return "<?xml version='1.0' encoding='UTF-8'?><program version='1.0'>" + "".join(tasks) + "</program>"


def task(body: str, name: str = "main", priority: int = 0) -> str:
    return f"<task name='{name}' priority='{priority}'>{body}</task>"


class Session:
    """A client of the server plus the protocol queue lines seen so far (GET_DEBUG_DATA keeps the last 32)."""

    def __init__(self, server: ServerThread, port_index: int = 0) -> None:
        self.server = server
        self.client = PlatformClient("127.0.0.1", server.ports[port_index], timeout=5.0)
        self.lines: list[str] = []

    def log(self) -> list[str]:
        """Every protocol queue line so far, in order (polled; call it often enough)."""
        queue = [e.entry for e in self.client.get_debug_data().protocol_queue]
        overlap = 0
        for k in range(min(len(queue), len(self.lines)), 0, -1):
            if self.lines[-k:] == queue[:k]:
                overlap = k
                break
        self.lines += queue[overlap:]
        return self.lines

    def saw(self, text: str) -> bool:
        return any(text in line for line in self.log())

    def wait_log(self, text: str, timeout: float = 10.0) -> list[str]:
        deadline = time.monotonic() + timeout
        while not self.saw(text):
            assert time.monotonic() < deadline, f"no log line with {text!r}; last lines: {self.lines[-12:]}"
            time.sleep(0.005)
        return self.lines

    def status(self) -> Status:
        return self.client.get_status()

    def wait_status(self, predicate: Callable[[Status], bool], timeout: float = 10.0, what: str = "") -> Status:
        return self.client.wait_until(predicate, timeout=timeout, poll=0.005, what=what or "condition")

    def run_local(self, xml: str, *, wait_finished: bool = True, timeout: float = 20.0) -> list[str]:
        """Set the program, MODE_MOTION_PROGRAM, CMD_START; by default wait for "program finished"."""
        c = self.client
        c.bring_up()
        status = c.get_status()
        if status.operation_state != OperationState.ST_OP_READY:
            c.stop()
            c.wait_state(OperationState.ST_OP_READY)
        c.set_mode(MotionMode.MODE_MOTION_PROGRAM)
        c.set_program(xml)
        c.start()
        c.wait_state(OperationState.ST_OP_RUNNING)
        return self.wait_log(FINISHED, timeout) if wait_finished else self.log()

    def run_remote(self, xml: str, data_dir: Path, *, seed: int = 1, timeout: float = 600.0) -> RunResult:
        prepare(self.client)
        machine = RemoteMachine(self.client, data_dir, EPOCH)
        return run_remote(
            load_program(xml.encode()), machine, time_scale=SCALE, seed=seed, period=0.005, timeout=timeout
        )

    def close(self) -> None:
        self.client.close()

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def program_server(data_dir: Path) -> ServerThread:
    """A started ServerThread whose platform runs the task interpreter on the fake hardware (as ``pltf serve``
    builds it, with the ideal motion model)."""
    return ServerThread(data_dir, time_scale=SCALE, program=factory, hardware=hardware_link.factory()).start()


@pytest.fixture
def server(tmp_path: Path) -> Iterator[ServerThread]:
    srv = program_server(tmp_path / "data")
    yield srv
    srv.stop()


@pytest.fixture
def session(server: ServerThread) -> Iterator[Session]:
    """A client of a platform brought up (CAN connected, boards initialized: their sections are reported)."""
    s = Session(server)
    s.client.bring_up()
    yield s
    s.close()
