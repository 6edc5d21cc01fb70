"""Fixtures of the fake-hardware tests: a platform built, connected and initialized at t = 0, a bus sniffer.

Every platform gets its own virtual channel, so the tests never see each other's frames. Time is simulated:
``run(hw, t0, t1)`` steps the hardware every ``DT`` like the server's control loop.
"""

from __future__ import annotations

import random
from collections.abc import Iterator
from typing import Any

import can
import pytest

from pltf.fake_hardware import Hardware, build_platform_hardware, candb

DT = 0.02


def run(hw: Hardware, t0: float, t1: float, dt: float = DT) -> tuple[float, list[Any]]:
    """Step from t0 (exclusive) to t1 (inclusive); the events of every step, and t1."""
    events: list[Any] = []
    n = round((t1 - t0) / dt)
    for k in range(1, n + 1):
        events += hw.step(t0 + k * dt)
    return t0 + n * dt, events


class Sniffer:
    """A plain python-can virtual bus on the platform's channel, decoding what it hears with the database."""

    def __init__(self, channel: str) -> None:
        self.bus = can.Bus(interface="virtual", channel=channel, preserve_timestamps=True)

    def frames(self) -> list[can.Message]:
        out = []
        while (frame := self.bus.recv(timeout=0)) is not None:
            out.append(frame)
        return out

    def decoded(self) -> list[tuple[str, dict[str, Any], can.Message]]:
        """Every frame heard since the last call, decoded; a frame the database does not know fails the test."""
        out = []
        for frame in self.frames():
            msg = candb.message_by_id(frame.arbitration_id)
            assert msg is not None, f"unknown CAN id 0x{frame.arbitration_id:03X}"
            assert len(frame.data) == msg.length, msg.name
            out.append((msg.name, dict(msg.decode(bytes(frame.data), decode_choices=False)), frame))
        return out

    def close(self) -> None:
        self.bus.shutdown()


@pytest.fixture
def make_hw() -> Iterator[Any]:
    made: list[Hardware] = []

    def make(**kwargs: Any) -> Hardware:
        kwargs.setdefault("rng", random.Random(7))
        kwargs.setdefault("scanner", None)
        hw = build_platform_hardware(**kwargs)
        made.append(hw)
        return hw

    yield make
    for hw in made:
        hw.close()


@pytest.fixture
def hw(make_hw: Any) -> Hardware:
    """All seven boards, connected and initialized at t = 0 (brakes released)."""
    hw: Hardware = make_hw()
    assert hw.connect(0.0).ok
    assert hw.init(0.0).ok
    return hw


@pytest.fixture
def sniffer(hw: Hardware) -> Iterator[Sniffer]:
    s = Sniffer(hw.channel)
    yield s
    s.close()
