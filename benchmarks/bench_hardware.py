"""Fake hardware rates: CAN frames through the controller, and the simulation's real-time factor.

The platform loop is the server's: every 20 ms of simulated time the hardware steps (all seven boards cycling,
the ultrasonic board measuring 16 sensors, the S300 streaming over ``sim://``), a minimal world integrates a
differential drive from the motors' wheel velocities and reports the wheel travel back, and the wheel setpoints
change every second. Time is simulated; the figures are wall-clock rates of that loop.

Benchmarks:
- ``hardware.can_throughput``: frames per wall-clock second received by the controller, on the ``SimVirtualBus``
  the platform uses and, as baseline, on python-can's stock ``VirtualBus`` (a deep copy and a locked queue per
  receiver). The bus load in simulated time (about 370 frames/s) is printed in the description.
- ``hardware.realtime_factor``: simulated seconds per wall second with the boards on, against the same loop with
  the boards off (the controller's math only: acceleration-limited wheels and odometry, no bus, no frames).
  Target: boards on >= 10x real time, so a minute of platform time costs at most 6 s of test time.
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable
from typing import Any
from unittest import mock

import can

from benchmarks.harness import Config, Row, Target, benchmark, make_row, median_times
from pltf.fake_hardware import hardware as hardware_module
from pltf.fake_hardware.boards.motor import MotorParams
from pltf.fake_hardware.hardware import Hardware, build_platform_hardware

DT = 0.02  # s: the server's control period
SIM_SECONDS = 20.0
SIM_SECONDS_QUICK = 1.0
TRACK = 430.0  # mm, DistWheels' default
RTF_TARGET = 10.0

SIM_BUS = "SimVirtualBus"
PLAIN_BUS = "python-can VirtualBus"
BOARDS_ON = "boards on"
BOARDS_OFF = "boards off (controller math only)"


def setpoints(t: float) -> tuple[float, float]:
    """A new wheel command every second: forward, arcs, turns on the spot."""
    rng = random.Random(int(t))
    return rng.uniform(-600, 600), rng.uniform(-600, 600)


class World:
    """The least a world can be: a differential drive integrated from the wheel velocities."""

    def __init__(self) -> None:
        self.x = self.y = self.angle = 0.0

    def move(self, vr: float, vl: float, dt: float) -> tuple[float, float]:
        dr, dl = vr * dt, vl * dt
        d, da = (dr + dl) / 2, (dr - dl) / TRACK
        self.x += d * math.cos(self.angle + da / 2)
        self.y += d * math.sin(self.angle + da / 2)
        self.angle += da
        return dr, dl


def ranges(t: float) -> list[float]:
    return [1500 + 800 * math.sin(t + i / 50) for i in range(541)]


def build(plain_bus: bool = False) -> Hardware:
    kwargs: dict[str, Any] = {"us_source": lambda t: [900 + 40 * i for i in range(16)], "scan_source": ranges}
    if not plain_bus:
        return build_platform_hardware(rng=random.Random(1), **kwargs)

    def plain(interface: str, channel: str, **kw: Any) -> can.BusABC:
        return can.Bus(interface="virtual", channel=channel, preserve_timestamps=True, **kw)

    with mock.patch.object(hardware_module, "open_bus", plain):
        return build_platform_hardware(rng=random.Random(1), **kwargs)


def run_boards_on(seconds: float, plain_bus: bool = False) -> int:
    """Simulate ``seconds`` of the platform loop with the hardware; the frames the controller received."""
    hw = build(plain_bus)
    try:
        assert hw.connect(0.0).ok and hw.init(0.0).ok
        hw.controller.start_ultrasonic(0xFFFF, 0.0)
        world = World()
        right, left = hw.motors
        assert right is not None and left is not None
        odo = World()
        for k in range(1, round(seconds / DT) + 1):
            t = k * DT
            hw.controller.set_wheel_velocities(*setpoints(t))
            hw.step(t)
            dr, dl = world.move(right.wheel_velocity, left.wheel_velocity, DT)
            right.report_wheel_travel(dr)
            left.report_wheel_travel(dl)
            er, el = hw.controller.take_wheel_travel()
            odo.move(er / DT, el / DT, DT)
        return int(hw.controller_port.stats.received)
    finally:
        hw.close()


def run_boards_off(seconds: float) -> int:
    """The same loop without hardware: ideal acceleration-limited wheels and odometry straight from them."""
    acc = MotorParams().acc_limit
    world, odo = World(), World()
    v = [0.0, 0.0]
    steps = round(seconds / DT)
    for k in range(1, steps + 1):
        target = setpoints(k * DT)
        for i in (0, 1):
            v[i] += max(-acc * DT, min(acc * DT, target[i] - v[i]))
        dr, dl = world.move(v[0], v[1], DT)
        odo.move(dr / DT, dl / DT, DT)
    return steps


def _seconds(config: Config) -> float:
    return SIM_SECONDS_QUICK if config.quick else SIM_SECONDS


@benchmark()
def can_throughput(config: Config) -> list[Row]:
    """CAN frames per second received by the controller, all boards cycling (SimVirtualBus vs VirtualBus)."""
    seconds = _seconds(config)
    frames = run_boards_on(seconds)
    if run_boards_on(seconds, plain_bus=True) != frames:
        raise AssertionError("the two buses carried different traffic")
    subjects: dict[str, Callable[[], object]] = {
        SIM_BUS: lambda: run_boards_on(seconds),
        PLAIN_BUS: lambda: run_boards_on(seconds, plain_bus=True),
    }
    times = median_times(subjects, config, number=1)
    rates = {name: frames / t for name, t in times.items()}
    return [
        make_row(
            "hardware.can_throughput",
            SIM_BUS,
            "controller_rx_rate",
            rates[SIM_BUS],
            "frames/s",
            higher_is_better=True,
            baseline_subject=PLAIN_BUS,
            baseline_value=rates[PLAIN_BUS],
        ),
        make_row(
            "hardware.can_throughput",
            PLAIN_BUS,
            "controller_rx_rate",
            rates[PLAIN_BUS],
            "frames/s",
            higher_is_better=True,
        ),
        make_row(
            "hardware.can_throughput",
            "simulated bus load",
            "controller_rx_rate",
            frames / seconds,
            "frames/sim-s",
            higher_is_better=True,
        ),
    ]


@benchmark()
def realtime_factor(config: Config) -> list[Row]:
    """Simulated seconds per wall second of the platform loop, boards on vs off."""
    seconds = _seconds(config)
    subjects: dict[str, Callable[[], object]] = {
        BOARDS_ON: lambda: run_boards_on(seconds),
        BOARDS_OFF: lambda: run_boards_off(seconds),
    }
    times = median_times(subjects, config, number=1)
    rtf = {name: seconds / t for name, t in times.items()}
    return [
        make_row(
            "hardware.realtime_factor",
            BOARDS_ON,
            "realtime_factor",
            rtf[BOARDS_ON],
            "sim-s/s",
            higher_is_better=True,
            baseline_subject=BOARDS_OFF,
            baseline_value=rtf[BOARDS_OFF],
            target=Target("value", ">=", RTF_TARGET),
        ),
        make_row(
            "hardware.realtime_factor", BOARDS_OFF, "realtime_factor", rtf[BOARDS_OFF], "sim-s/s", higher_is_better=True
        ),
    ]
