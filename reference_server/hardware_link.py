"""The fake hardware behind the platform model (fake_hardware/): one ``HardwareLink`` per platform.

Rules:
- Built by a factory like ``motion`` and ``program``: ``Platform(..., hardware=factory(...))``, ``factory(...)``
  gives ``build(platform) -> HardwareLink``. Without it the platform has ideal wheels and no boards
  (``motion_api.advance_ideal``, every board section ABSENT), as before.
- The controller knows the boards only through CAN frames; this module calls only the public side of
  ``fake_hardware.Hardware`` / ``CanController`` (fake_hardware/README.md) and never sets a board's state.
- One control period (``advance``), in the order of reference_server/motion_api.py: ``motion.step`` -> the
  wheel setpoints to the controller (CAN frames) -> ``hardware.step(now)`` -> the motors' wheel velocities ->
  ``motion.move`` (the true body; the real wheel travel goes back to the motor boards) -> the wheel travel of the
  encoder frames -> ``motion.odometry``. The motion model's sensor sources feed the ultrasonic board, the gyro
  board and the serial laser scanner.
- Hardware events map to the platform (``react``): the emergency stop to ``Platform.set_emergency``, a drive
  fault (a motor lost, absent or over-temperature, the controller bus-off) to ``Platform.set_drive_fault``, the
  end of a deferred self test to the state chart's CMD_INIT_PLTF transition (erratum E-HW-024, E-HW-025).
- Sans-IO: ``now`` comes from the caller; the hardware's random parts are seeded from ``Platform.random``.
"""

from __future__ import annotations

import logging
import math
import random
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from pltf.fake_hardware import ALL_NODES, Hardware, HwEvent, Node, St, Transaction, build_platform_hardware
from pltf.fake_hardware.controller import HARDWARE_FAULTS
from pltf.fake_hardware.serial_scanner import ANGLE_STEP, MAX_CM, POINTS, START_ANGLE, Ranges, Scan
from pltf.reference_server.motion_api import MotionModel, WorldFeatures

if TYPE_CHECKING:
    from pltf.reference_server.platform import Platform

HardwareFactory = Callable[["Platform"], "HardwareLink"]
AUTO = "auto"
NO_ECHO = MAX_CM * 10  # mm: what the S300 sends for a beam without echo
# each beam's direction, from math.cos/sin (numpy's may differ in the last bit): the points are exact
_COS = np.array([math.cos(START_ANGLE + i * ANGLE_STEP) for i in range(POINTS)])
_SIN = np.array([math.sin(START_ANGLE + i * ANGLE_STEP) for i in range(POINTS)])
_I16 = 32767


def factory(
    interface: str = "virtual",
    channel: str | None = None,
    *,
    scanner: str | None = AUTO,
    nodes: Iterable[Node] = ALL_NODES,
    expected: Iterable[Node] | None = None,
) -> HardwareFactory:
    """A hardware factory: all seven boards on ``interface``/``channel`` (None: a channel of its own) and the S300
    on ``scanner`` (a pyserial URL; ``AUTO``: ``sim://`` when the motion model is a world with surroundings to
    scan, none for the ideal ``kinematics.Drive``, whose status reports no scan either)."""
    fitted, probed = tuple(nodes), None if expected is None else tuple(expected)

    def build(p: Platform) -> HardwareLink:
        motion = p.motion
        link = scanner if scanner != AUTO else ("sim://" if isinstance(motion, WorldFeatures) else None)
        hw = build_platform_hardware(
            interface,
            channel,
            p.params.get,
            random.Random(p.random.getrandbits(64)),
            nodes=fitted,
            expected=probed,
            scanner=link,
            scan_source=lambda now: _ranges(motion.scan_ranges(now), POINTS),
            us_source=lambda now: _ranges(motion.us_ranges(now), 16),
            motion_source=motion.imu,
        )
        return HardwareLink(hw, motion)

    return build


_NONE: dict[int, tuple[None, ...]] = {POINTS: (None,) * POINTS, 16: (None,) * 16}


_R = TypeVar("_R", bound=Ranges)


def _ranges(values: _R | None, n: int) -> _R | tuple[None, ...]:
    return _NONE[n] if values is None else values


class HardwareLink:
    def __init__(self, hw: Hardware, motion: MotionModel) -> None:
        self.hw = hw
        self.controller = hw.controller
        self.motion = motion
        self.connect_txn: Transaction | None = None
        self.init_txn: Transaction | None = None
        self.init_deferred = False  # CMD_INIT_PLTF arrived while the probe still waited (erratum E-HW-024)
        self._low_battery = False
        self._scan_points: tuple[Scan | None, tuple[tuple[int, int], ...]] = (None, ())

    # ---- CAN communication commands (guide 6.3)
    def connect(self, now: float) -> Transaction:
        self.init_txn, self.init_deferred = None, False
        self.connect_txn = self.hw.connect(now)
        return self.connect_txn

    def init(self, now: float) -> Transaction | None:
        """Start the self test; None when it waits for the probe of the connect (it starts when that is done)."""
        if self.connect_txn is not None and not self.connect_txn.done:
            self.init_deferred = True
            return None
        self.init_deferred = False
        self.init_txn = self.hw.init(now)
        return self.init_txn

    def shutdown(self, now: float) -> None:
        self.connect_txn, self.init_txn, self.init_deferred = None, None, False
        self.hw.shutdown(now)

    def connected(self, node: Node) -> bool:
        return node in self.controller.connected

    # ---- the control period
    def advance(self, now: float, dt: float) -> tuple[list[str], list[HwEvent]]:
        """One control period (see the module rules); the motion model's log lines and the hardware's events."""
        motion, c = self.motion, self.controller
        lines = motion.step(now, dt) if dt > 0.0 else []
        c.set_wheel_velocities(*motion.wheel_setpoints())
        events = self.hw.step(now)
        if self.init_deferred and self.connect_txn is not None and self.connect_txn.done:
            self.init(now)
        right, left = self.hw.motors
        if dt > 0.0:
            vr = right.wheel_velocity if right is not None else 0.0
            vl = left.wheel_velocity if left is not None else 0.0
            travel_r, travel_l = motion.move(vr, vl, dt)
            if right is not None:
                right.report_wheel_travel(travel_r)
            if left is not None:
                left.report_wheel_travel(travel_l)
            motion.odometry(*c.take_wheel_travel(), dt)
        events += self._battery()
        return lines, events

    def _battery(self) -> list[HwEvent]:
        low = Node.IOBOARD in self.controller.connected and bool(
            self.controller.status_word(Node.IOBOARD) & St.LOW_BATTERY
        )
        if low == self._low_battery:
            return []
        self._low_battery = low
        mv = self.controller.board_status().io_battery_voltage
        text = f"IO board: battery low ({mv} mV)" if low else f"IO board: battery voltage back to {mv} mV"
        return [HwEvent("battery_low" if low else "battery_ok", Node.IOBOARD, text)]

    # ---- what the platform reads
    def drive_fault(self) -> str | None:
        """Why the drives cannot be trusted now (erratum E-HW-025); None while the bus is down or all is well.

        The emergency stop has its own state; a brake engaged by CMD_SET_BRAKE is the client's wish."""
        c = self.controller
        if not c.bus_up:
            return None
        if c.bus_off:
            return "CAN bus-off"
        return c.motor_fault(HARDWARE_FAULTS, absent="not connected")

    @property
    def emergency_active(self) -> bool:
        return self.controller.emergency_active

    def board_fields(self) -> dict[str, Any]:
        """The board sections of CMD_GET_STATUS (fake_hardware/board_status.py)."""
        return self.controller.board_status().as_fields()

    def scan_points(self, mount_x: float) -> tuple[tuple[int, int], ...] | None:
        """The last valid scan of the serial scanner in platform coordinates (mm); None: no scanner fitted,
        () while it is silent (erratum E-HW-026)."""
        reader = self.hw.scan_reader
        if reader is None:
            return None
        if not self.hw.scanner_ok or reader.last_scan is None:
            return ()
        scan = reader.last_scan
        if self._scan_points[0] is not scan:
            self._scan_points = (scan, scan_to_platform(scan.ranges_mm, mount_x))
        return self._scan_points[1]

    def close(self) -> None:
        self.hw.close()


def scan_to_platform(ranges_mm: tuple[int, ...], mount_x: float) -> tuple[tuple[int, int], ...]:
    """The beams with an echo as (x, y) in platform coordinates, mm, rounded half to even and saturated to
    INT16 (the scan group of guide 6.4), in one numpy pass: a client polling GET_STATUS at 20 Hz meets a new
    scan at nearly every request, and a loop over the 541 beams was most of the reply's cost."""
    r = np.asarray(ranges_mm, dtype=np.float64)
    n = len(r)
    echo = (r > 0) & (r < NO_ECHO)
    r = r[echo]
    xy = np.stack((mount_x + r * _COS[:n][echo], r * _SIN[:n][echo]), axis=1)
    ints = np.clip(np.rint(xy), -_I16, _I16).astype(np.int64)
    return tuple(map(tuple, ints.tolist()))


# ---- hardware events -> platform (emergency, drive fault, the deferred self test)
def react(p: Platform, link: HardwareLink, events: list[HwEvent], now: float) -> None:
    for event in events:
        action = REACTIONS.get(event.kind)
        p.log(LOG_LEVEL.get(event.kind, logging.INFO), "%s", event.text)
        if action is not None:
            action(p, link, now)
    p.set_drive_fault(link.drive_fault(), now)


def _pressed(p: Platform, link: HardwareLink, now: float) -> None:
    p.set_emergency(True, now)


def _released(p: Platform, link: HardwareLink, now: float) -> None:
    p.set_emergency(False, now)


def _connect_done(p: Platform, link: HardwareLink, now: float) -> None:
    # the emergency state the platform kept over a shutdown meets the relay board's present word
    if link.emergency_active != p.emergency_pressed:
        p.set_emergency(link.emergency_active, now)


def _init_done(p: Platform, link: HardwareLink, now: float) -> None:
    if p.awaiting == "CMD_INIT_PLTF":
        p.awaiting = None
        txn = link.init_txn
        if txn is not None and txn.ok:
            p.fire("CMD_INIT_PLTF")
        else:
            p.log(logging.WARNING, "platform not initialized: the self test failed (CMD_INIT_PLTF may be sent again)")


REACTIONS: dict[str, Callable[[Platform, HardwareLink, float], None]] = {
    "emergency_pressed": _pressed,
    "emergency_released": _released,
    "connect_done": _connect_done,
    "init_done": _init_done,
}
LOG_LEVEL = dict.fromkeys(
    ("node_lost", "frames_lost", "bus_off", "emergency_pressed", "scanner_lost", "battery_low"), logging.WARNING
)
