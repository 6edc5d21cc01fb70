"""The plug-in seams of the platform: the command table, the motion model, the program hook."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import pytest

from pltf.reference_server.commands import HANDLERS, handles
from pltf.reference_server.kinematics import Drive, Frame
from pltf.reference_server.motion_api import MotionModel, Params
from pltf.reference_server.platform import Platform
from pltf.reference_server.program_api import NoProgram
from pltf.reference_server.storage import Storage
from pltf.spec.codec import REQUESTS
from pltf.spec.model import enum_classes

R = REQUESTS
MotionMode: Any = enum_classes()["MotionMode"]
DT = 0.02


class Recorder:
    """A program that records what the platform asks of it."""

    def __init__(self, platform: Platform) -> None:
        self.calls: list[str] = []
        self.ticks = 0

    def start(self, now: float) -> None:
        self.calls.append("start")

    def pause(self, now: float) -> None:
        self.calls.append("pause")

    def resume(self, now: float) -> None:
        self.calls.append("resume")

    def stop(self, now: float) -> None:
        self.calls.append("stop")

    def tick(self, now: float) -> None:
        self.ticks += 1


def platform(tmp_path: Path, **kwargs: Any) -> Platform:
    storage = Storage(tmp_path / "data")
    storage.seed_from_fixtures()
    p = Platform(storage, seed=1, **kwargs)
    p.boot(0.0)
    return p


def to_ready(p: Platform, mode: int) -> None:
    for t in (R.CMD_CONNECT_TO_PLTF(), R.CMD_INIT_PLTF(), R.CMD_SET_MODE(mode=mode)):
        assert p.handle(t, 0.0).refused is None


def test_a_handler_is_registered_once() -> None:
    with pytest.raises(ValueError, match="already has a handler"):
        handles("CMD_START")(HANDLERS["CMD_START"])
    assert HANDLERS["CMD_START"].__module__ == "pltf.reference_server.commands.operation"


def test_operation_commands_drive_the_program_in_program_mode(tmp_path: Path) -> None:
    p = platform(tmp_path, program=Recorder)
    program = p.program
    assert isinstance(program, Recorder)
    to_ready(p, MotionMode.MODE_MOTION_PROGRAM)
    for t in (R.CMD_START(), R.CMD_BREAK(), R.CMD_CONTINUE(), R.CMD_STOP(), R.CMD_START()):
        assert p.handle(t, 0.0).refused is None
    assert program.calls == ["start", "pause", "resume", "stop", "start"]
    for k in range(1, 6):
        p.tick(k * DT)
    assert program.ticks == 5
    p.set_emergency(True, 0.2)  # leaving Running any other way stops the program too
    assert program.calls[-1] == "stop"


def test_other_modes_leave_the_program_alone(tmp_path: Path) -> None:
    p = platform(tmp_path, program=Recorder)
    to_ready(p, MotionMode.MODE_MOTION_AUTOMATIC)
    for t in (R.CMD_START(), R.CMD_BREAK(), R.CMD_CONTINUE(), R.CMD_STOP()):
        p.handle(t, 0.0)
    assert isinstance(p.program, Recorder) and p.program.calls == []


def test_the_default_program_logs_that_there_is_none(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    p = platform(tmp_path)
    assert isinstance(p.program, NoProgram)
    to_ready(p, MotionMode.MODE_MOTION_PROGRAM)
    with caplog.at_level(logging.WARNING, logger="pltf.server"):
        p.handle(R.CMD_START(), 0.0)
    assert "no program loaded" in caplog.text
    assert any("no program loaded" in line for line in p.protocol_queue)


def test_the_motion_model_is_a_plug_in(tmp_path: Path) -> None:
    built: list[MotionModel] = []

    def factory(params: Params) -> MotionModel:
        built.append(Drive(params))
        return built[-1]

    p = platform(tmp_path, motion=factory)
    assert p.motion is built[0] and p.drive is p.motion
    start = p.motion.true_pose.frame()
    assert p.motion.pose.frame() == start  # the start pose places the body and the estimate
    p.handle(R.CMD_SET_FRM_PLTF(x=100, y=200, angle=90_000), 0.0)
    assert p.motion.pose.frame()[:2] == (100, 200)
    assert p.motion.true_pose.frame() == start  # CMD_SET_FRM_PLTF: the estimate only (E-HW-023)


def test_truth_and_estimate_move_together_without_hardware(tmp_path: Path) -> None:
    p = platform(tmp_path)
    to_ready(p, MotionMode.MODE_MOTION_AUTOMATIC)
    p.handle(R.CMD_START(), 0.0)
    p.handle(R.CMD_MOVE_REL(x=500, y=0, angle=0), 0.0)
    for k in range(1, 200):
        p.tick(k * DT)
    est, true = p.motion.pose.frame(), p.motion.true_pose.frame()
    assert est == pytest.approx(true) and est.x > 2400
    assert p.motion.commanded_frame() == pytest.approx(Frame(est.x, est.y, est.angle))
