"""One platform's fake hardware: the boards on one CAN channel, the controller, the laser scanner, the faults.

Rules:
- ``build_platform_hardware`` is the one constructor the server needs. Each platform instance gets its own
  channel (``pltf-<n>`` on the virtual bus, unique in the process), so parallel tests never cross-talk.
- ``Hardware.step(now)`` is the one call per control tick, at least every 20 ms of simulated time (the motors'
  encoder cycle): scheduled faults, then every board, the scanner, the controller and the scan reader. A
  request the controller sends in one tick is answered by the boards in the next one.
- ``connect``/``init`` start the controller's transaction and run one step at the same ``now``, so on a complete
  platform they are done on return; a missing node makes them last until their simulated deadline. The events
  of that inner step come out of the next ``step``.
- The world simulation (later) reads ``motors[i].wheel_velocity`` after ``step`` and may report the true
  wheel travel back (``report_wheel_travel``) before the next one; range callbacks feed the ultrasonic board
  and the scanner.
"""

from __future__ import annotations

import itertools
import random
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from pltf.fake_hardware.boards import (
    Board,
    EmergencyCircuit,
    GyroBoard,
    IoBoard,
    MotorBoard,
    MotorParams,
    RadarBoard,
    RelayBoard,
    UltrasonicBoard,
)
from pltf.fake_hardware.boards.gyro import MotionSource
from pltf.fake_hardware.boards.radar import VelocitySource
from pltf.fake_hardware.boards.ultrasonic import RangeSource as UsRangeSource
from pltf.fake_hardware.candb import ALL_NODES, Node
from pltf.fake_hardware.canport import BusConditions, CanPort, open_bus
from pltf.fake_hardware.controller import CanController, HwEvent, Params, Transaction
from pltf.fake_hardware.faults import FaultInjector
from pltf.fake_hardware.serial_scanner import RangeSource, S300Simulator, Scan, ScanReader, SerialLink, open_serial_link

_channels = itertools.count(1)


@dataclass
class Hardware:
    interface: str
    channel: str
    controller: CanController
    controller_port: CanPort
    boards: dict[Node, Board]
    ports: dict[Node, CanPort]
    circuit: EmergencyCircuit
    conditions: BusConditions
    link: SerialLink | None = None
    scanner: S300Simulator | None = None
    scan_reader: ScanReader | None = None
    scans: list[Scan] = field(default_factory=list)  # the scans read in the last step
    faults: FaultInjector = field(init=False)
    _scanner_silent: bool = False
    _carry: list[HwEvent] = field(default_factory=list)  # events of the steps inside connect/init/shutdown

    def __post_init__(self) -> None:
        self.faults = FaultInjector(self)

    @property
    def motors(self) -> tuple[MotorBoard | None, MotorBoard | None]:
        """The right and left motor boards (None when not fitted)."""
        right, left = (self.boards.get(n) for n in (Node.MOTOR_RIGHT, Node.MOTOR_LEFT))
        return (right if isinstance(right, MotorBoard) else None, left if isinstance(left, MotorBoard) else None)

    def step(self, now: float) -> list[HwEvent]:
        events, self._carry = self._carry, []
        events += self.faults.step(now)
        for board in self.boards.values():
            board.step(now)
        if self.scanner is not None:
            self.scanner.step(now)
        events += self.controller.step(now)
        if self.scan_reader is not None:
            self.scans = self.scan_reader.poll(now)
            silent = self.scan_reader.silent(now)
            if silent != self._scanner_silent:
                self._scanner_silent = silent
                text = "laser scanner silent" if silent else "laser scanner sends again"
                events.append(HwEvent("scanner_lost" if silent else "scanner_back", None, text))
        return events

    @property
    def scanner_ok(self) -> bool:
        return self.scan_reader is not None and not self._scanner_silent

    def connect(self, now: float) -> Transaction:
        """CMD_CONNECT_TO_PLTF: probe every node; done on return unless a node is missing."""
        txn = self.controller.connect(now)
        self._carry = self.step(now)
        return txn

    def init(self, now: float) -> Transaction:
        """CMD_INIT_PLTF: self test of every connected node; done on return unless a node does not answer."""
        txn = self.controller.init(now)
        self._carry = self.step(now)
        return txn

    def shutdown(self, now: float) -> None:
        """CMD_SHUTDOWN_PLTF."""
        self.controller.shutdown(now)
        self._carry = self.step(now)

    def close(self) -> None:
        for port in [*self.ports.values(), self.controller_port]:
            port.close()
        if self.link is not None:
            self.link.close()

    def __enter__(self) -> Hardware:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def build_platform_hardware(
    interface: str = "virtual",
    channel: str | None = None,
    params: Params | None = None,
    rng: random.Random | None = None,
    *,
    nodes: Iterable[Node] = ALL_NODES,
    expected: Iterable[Node] | None = None,
    scanner: str | None = "sim://",
    scan_source: RangeSource | None = None,
    us_source: UsRangeSource | None = None,
    radar_source: VelocitySource | None = None,
    motion_source: MotionSource | None = None,
    bus_kwargs: dict[str, Any] | None = None,
) -> Hardware:
    """One platform's hardware.

    ``nodes``: the boards fitted (default all seven); ``expected``: the nodes the controller probes (default the
    same; name more to simulate a missing board); ``scanner``: the S300's link (``sim://``, another pyserial URL,
    ``"pty"``, or None for none); ``rng`` seeds every random part (initial encoder positions, frame loss, serial
    corruption); ``params`` is the server's parameter lookup (``RadiusWheel`` is read from it).
    """
    rng = rng or random.Random(0)
    if channel is None:
        if interface != "virtual":
            raise ValueError(f"interface {interface!r} needs a channel (e.g. vcan0)")
        channel = f"pltf-{next(_channels)}"
    kwargs = bus_kwargs or {}
    conditions = BusConditions(rng=random.Random(rng.getrandbits(64)))
    circuit = EmergencyCircuit()
    radius = float(params("RadiusWheel")) if params else MotorParams().wheel_radius
    motor_params = MotorParams(wheel_radius=radius)

    def motor(node: Node) -> Callable[[CanPort], Board]:
        return lambda p: MotorBoard(node, p, circuit, motor_params, tick_offset=rng.randrange(-(2**31), 2**31))

    makers: dict[Node, Callable[[CanPort], Board]] = {
        Node.IOBOARD: IoBoard,
        Node.MOTOR_RIGHT: motor(Node.MOTOR_RIGHT),
        Node.MOTOR_LEFT: motor(Node.MOTOR_LEFT),
        Node.USBOARD: lambda p: UltrasonicBoard(p, us_source),
        Node.RELAYBOARD: lambda p: RelayBoard(p, circuit),
        Node.RADARBOARD: lambda p: RadarBoard(p, radar_source),
        Node.GYROBOARD: lambda p: GyroBoard(p, motion_source),
    }
    ports: dict[Node, CanPort] = {}
    boards: dict[Node, Board] = {}
    for node in sorted(set(nodes)):
        ports[node] = CanPort(open_bus(interface, channel, **kwargs), conditions, node.name)
        boards[node] = makers[node](ports[node])
    controller_port = CanPort(open_bus(interface, channel, **kwargs), conditions, "PLTF_CTRL")
    controller = CanController(
        controller_port,
        nodes=boards if expected is None else expected,
        params=params,
        ticks_per_rev=motor_params.ticks_per_rev,
        stamp="frame" if interface == "virtual" else "receive",
    )
    hw = Hardware(interface, channel, controller, controller_port, boards, ports, circuit, conditions)
    if scanner is not None:
        hw.link = open_serial_link(scanner)
        hw.scan_reader = ScanReader(hw.link.host)
        if hw.link.device is not None:
            hw.scanner = S300Simulator(hw.link.device, scan_source, rng=random.Random(rng.getrandbits(64)))
    return hw
