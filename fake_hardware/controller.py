"""The controller side of the CAN bus: what PlatformCtrl does with the boards (guide 4.2, 6.3 CAN commands).

Rules:
- Sans-IO in spirit: every call takes simulated ``now``; ``step(now)`` polls the port without blocking,
  handles what arrived, checks timeouts, finishes transactions and sends the cyclic wheel setpoints. No sleeps,
  no clock. The owner calls ``step`` after the boards' ``step`` at every control tick (50 Hz simulated).
- The controller knows the boards only through frames of the CAN database: a node that does not answer the
  probe is reported missing and stays ABSENT in the status (never faked, erratum E-HW-003).
- Connect and init are transactions (``Transaction``): requests go out at once, answers are collected by later
  ``step`` calls, and the transaction is done when every node answered or its simulated deadline passed.
- The bus is "down" until CMD_CONNECT_TO_PLTF and after CMD_SHUTDOWN_PLTF: frames are drained and ignored.
- Wheel travel comes only from encoder ticks (int32, wrap-safe deltas) with the radius read through ``params``
  on every frame (``RadiusWheel``), so a changed parameter really changes the odometry (erratum E-HW-007).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from typing import Any, Literal

import can

from pltf.fake_hardware import candb
from pltf.fake_hardware.board_status import BoardStatus, assemble
from pltf.fake_hardware.candb import ALL_NODES, MOTORS, PREFIX, Node, St
from pltf.fake_hardware.canport import CanPort
from pltf.fake_hardware.records import CanRecord, ControllerError, HwEvent, SelfTestResult, Transaction

__all__ = ["CanController", "CanRecord", "ControllerError", "HwEvent", "SelfTestResult", "Transaction"]

PROBE_TIMEOUT = 0.1  # s: connect waits this long for the probe replies
SELFTEST_TIMEOUT = 0.5  # s
NODE_TIMEOUT = 0.5  # s without any frame from a connected node: NODE_TIMEOUT (5 periods of the slowest cycle)
FRAME_LOSS_HOLD = 1.0  # s that FRAMES_LOST stays set after a counter gap
LISTEN_BUFFER = 10_000  # frames kept for CMD_GET_CAN_MESSAGES; the oldest go first
CAN_ERR_BUSOFF = 0x40  # SocketCAN error-frame class bits (linux/can/error.h)
CAN_ERR_RESTARTED = 0x100
DEFAULT_TICKS_PER_REV = 4096 * 20
DEFAULT_RADIUS = 130.0  # mm, RadiusWheel's default
BOARD_TYPES = {0: Node.IOBOARD, 1: Node.RELAYBOARD}  # CMD_SET_DIGOUT board type -> node
DIGOUT_CHANNELS = {Node.IOBOARD: 16, Node.RELAYBOARD: 8}
ANSWERS = {"ProbeReply": "connect", "SelfTestResult": "init"}  # answer -> transaction kind

Params = Callable[[str], Any]


# A motor board's status bits that keep its wheel from following setpoints (drive_fault), most telling first;
# the first two are hardware faults whatever the client did (the reference server's E-HW-025 check).
MOTOR_FAULTS: tuple[tuple[int, str], ...] = (
    (St.NODE_TIMEOUT, "not answering"),
    (St.OVER_TEMPERATURE, "over-temperature"),
    (St.NOT_INITIALIZED, "not initialized"),
    (St.BRAKE_ENGAGED, "brake engaged"),
)
HARDWARE_FAULTS = MOTOR_FAULTS[:2]


class CanController:
    def __init__(
        self,
        port: CanPort,
        nodes: Iterable[Node] = ALL_NODES,
        params: Params | None = None,
        ticks_per_rev: int = DEFAULT_TICKS_PER_REV,
        stamp: Literal["frame", "receive"] = "frame",
    ) -> None:
        self.port = port
        self.nodes = tuple(sorted(set(nodes)))
        self.params = params
        self.ticks_per_rev = ticks_per_rev
        self.stamp = stamp  # "frame": trust frame timestamps (virtual bus); "receive": stamp with now
        self.bus_up = False
        self.connected: set[Node] = set()
        self.initialized = False
        self.now = 0.0
        self.transaction: Transaction | None = None
        self.listening: set[int] = set()
        self.frames_lost: dict[Node, int] = dict.fromkeys(MOTORS, 0)
        self._buffer: deque[CanRecord] = deque(maxlen=LISTEN_BUFFER)
        self._readings: dict[Node, dict[str, dict[str, Any]]] = {}
        self._readings_serial = 0  # counts the changes of _readings and connected (board_status' memo key)
        self._board_memo: tuple[tuple[int, tuple[int, ...]], BoardStatus] | None = None
        self._board_bits: dict[Node, int] = {}
        self._last_rx: dict[Node, float] = {}
        self._lost: set[Node] = set()
        self._loss_until: dict[Node, float] = {}
        self._counters: dict[Node, int] = {}
        self._ticks: dict[Node, int] = {}
        self._travel: dict[Node, float] = dict.fromkeys(MOTORS, 0.0)
        self._taken: dict[Node, float] = dict.fromkeys(MOTORS, 0.0)
        self._setpoints: dict[Node, int] = dict.fromkeys(MOTORS, 0)
        self._setpoint_counter = 0
        self._sequence = 0
        self._error_bus_off = False
        self._was_bus_off = False
        self._was_emergency = False
        self._rx: dict[int, tuple[Node, str, Any]] = {}
        for node in ALL_NODES:
            for msg in candb.database().messages:
                if msg.frame_id >> 8 == node and msg.senders == [node.name]:
                    self._rx[msg.frame_id] = (node, msg.name.removeprefix(PREFIX[node] + "_"), msg)

    # ------------------------------------------------------------------ CMD_CONNECT/INIT/SHUTDOWN_PLTF
    def connect(self, now: float) -> Transaction:
        """Bring the bus up and probe every configured node; missing nodes are known when it is done."""
        self._reset()
        self.bus_up = True
        self.port.poll(now)  # what was on the bus before the connect is not ours
        txn = self._start("connect", now, PROBE_TIMEOUT, set(self.nodes))
        for node in self.nodes:
            self._send(node, "Probe", {"Sequence": txn.sequence}, now)
        return txn

    def init(self, now: float) -> Transaction:
        """Self test of every connected node (CMD_INIT_PLTF); a motor that passes gets its brake released."""
        if not self.bus_up:
            raise ControllerError("CAN bus not connected")
        txn = self._start("init", now, SELFTEST_TIMEOUT, set(self.connected))
        for node in sorted(self.connected):
            self._send(node, "SelfTest", {"Sequence": txn.sequence}, now)
        return txn

    def shutdown(self, now: float) -> None:
        """CMD_SHUTDOWN_PLTF: the nodes stop, the bus goes down."""
        for node in sorted(self.connected):
            self._send(node, "Shutdown", {}, now)
        self._reset()

    # ------------------------------------------------------------------ commands
    def set_wheel_velocities(self, right: float, left: float) -> None:
        """Wheel surface velocities in mm/s; sent at every ``step`` while initialized (erratum E-HW-008)."""
        self._setpoints = {Node.MOTOR_RIGHT: _int16(right), Node.MOTOR_LEFT: _int16(left)}

    def set_brake(self, motor: int, released: bool, now: float) -> None:
        """CMD_SET_BRAKE: motor 1 right, 2 left; released True = "1: Brake disabled" (E-CMD-015)."""
        node = Node(motor) if motor in (1, 2) else None
        if node is None:
            raise ControllerError(f"no motor {motor}")
        self._require()
        self._send(node, "Brake", {"Release": int(released)}, now)

    def set_digout(self, board: int, channel: int, value: bool, now: float) -> None:
        """CMD_SET_DIGOUT: board 0 IO board (16 outputs), 1 relay board (8 relays), erratum E-HW-010."""
        node = BOARD_TYPES.get(board)
        if node is None or not 0 <= channel < DIGOUT_CHANNELS[node]:
            raise ControllerError(f"no digital output {channel} on board type {board}")
        self._require()
        function = "DigOut" if node == Node.IOBOARD else "RelayOut"
        self._send(node, function, {"Channel": channel, "Value": int(value)}, now)

    def start_ultrasonic(self, mask: int, now: float) -> None:
        """CMD_START_ULTRASONIC: bit n = sensor n+1 (E-CMD-005)."""
        if not 0 <= mask <= 0xFFFF:
            raise ControllerError(f"ultrasonic mask {mask} out of range")
        self._require()
        self._send(Node.USBOARD, "Start", {"ActiveMask": mask}, now)

    def stop_ultrasonic(self, now: float) -> None:
        self._require()
        self._send(Node.USBOARD, "Stop", {}, now)

    # ------------------------------------------------------------------ raw CAN (6.3 CAN commands)
    def add_listening_id(self, can_id: int) -> None:
        _check_id(can_id)
        self.listening.add(can_id)

    def remove_listening_id(self, can_id: int) -> None:
        _check_id(can_id)
        self.listening.discard(can_id)

    def send_can_message(self, can_id: int, data: bytes, now: float) -> bool:
        """CMD_SEND_CAN_MESSAGE: an 8-byte standard frame; False when the bus is down or the frame was lost."""
        _check_id(can_id)
        if len(data) > 8:
            raise ControllerError("a CAN frame carries at most 8 bytes")
        if not self.bus_up:
            return False
        frame = can.Message(arbitration_id=can_id, data=bytes(data).ljust(8, b"\0"), is_extended_id=False)
        return self.port.send(frame, now)

    def get_can_messages(self, delete: bool) -> list[CanRecord]:
        """CMD_GET_CAN_MESSAGES: the buffered frames of the listening ids, oldest first; ``delete`` empties it."""
        out = list(self._buffer)
        if delete:
            self._buffer.clear()
        return out

    # ------------------------------------------------------------------ the loop
    def step(self, now: float) -> list[HwEvent]:
        self.now = now
        events: list[HwEvent] = []
        frames = self.port.poll(now)
        if self.bus_up:
            for frame in frames:
                self._receive(frame, now, events)
        self._check_bus_off(events)
        self._check_timeouts(now, events)
        self._check_transaction(now, events)
        self._check_emergency(events)
        if self.bus_up and self.initialized:
            self._setpoint_counter = (self._setpoint_counter + 1) & 0xFF
            for node in MOTORS:
                if node in self.connected:
                    self._send(
                        node, "Setpoint", {"Velocity": self._setpoints[node], "Counter": self._setpoint_counter}, now
                    )
        return events

    # ------------------------------------------------------------------ what the server reads
    def board_status(self) -> BoardStatus:
        """The snapshot; assembled again only when a reading arrived or a status word changed since the last
        one (a server asked for its status hundreds of times a second between two CAN cycles)."""
        words = tuple(self.status_word(node) for node in ALL_NODES)
        key = (self._readings_serial, words)
        if self._board_memo is None or self._board_memo[0] != key:
            readings = {n: r for n, r in self._readings.items() if n in self.connected}
            self._board_memo = (key, assemble(readings, dict(zip(ALL_NODES, words, strict=True))))
        return self._board_memo[1]

    def status_word(self, node: Node) -> int:
        if node not in self.connected:
            return St.ABSENT
        word = self._board_bits.get(node, 0)
        if node in self._lost:
            word |= St.NODE_TIMEOUT
        if self._loss_until.get(node, -math.inf) > self.now:
            word |= St.FRAMES_LOST
        if self.bus_off:
            word |= St.BUS_OFF
        return word

    @property
    def bus_off(self) -> bool:
        return self.port.bus_off or self._error_bus_off

    @property
    def emergency_active(self) -> bool:
        """The emergency-stop circuit is open, as the relay board or a motor board reports it."""
        state = self._readings.get(Node.RELAYBOARD, {}).get("State")
        if Node.RELAYBOARD in self.connected and state is not None and state["EmergencyCircuitOpen"]:
            return True
        return any(self._board_bits.get(m, 0) & St.EMERGENCY_STOP for m in MOTORS if m in self.connected)

    def drive_fault(self) -> str | None:
        """Why the wheels cannot follow setpoints now (None: they can)."""
        if not self.bus_up:
            return "CAN bus not connected"
        if self.bus_off:
            return "CAN bus-off"
        if self.emergency_active:
            return "emergency stop"
        return self.motor_fault(MOTOR_FAULTS)

    def motor_fault(self, faults: Sequence[tuple[int, str]], absent: str = "absent") -> str | None:
        """The first motor board that is absent or shows one of ``faults`` (status bit, text), as
        "MOTOR_RIGHT <text>"; None when neither does."""
        for m in MOTORS:
            word = self.status_word(m)
            if word == St.ABSENT:
                return f"{m.name} {absent}"
            for bit, text in faults:
                if word & bit:
                    return f"{m.name} {text}"
        return None

    @property
    def wheel_travel(self) -> tuple[float, float]:
        """Travel of the right and left wheel in mm since the connect, from the encoder ticks."""
        return self._travel[Node.MOTOR_RIGHT], self._travel[Node.MOTOR_LEFT]

    def take_wheel_travel(self) -> tuple[float, float]:
        """Wheel travel (right, left) in mm since the previous call: the odometry increment."""
        out = tuple(self._travel[m] - self._taken[m] for m in MOTORS)
        self._taken = dict(self._travel)
        return out[0], out[1]

    @property
    def wheel_velocities(self) -> tuple[float, float]:
        """Measured wheel velocities (right, left) in mm/s, from the Encoder frames."""
        right, left = (float(self._readings.get(m, {}).get("Encoder", {}).get("Velocity", 0)) for m in MOTORS)
        return right, left

    # ------------------------------------------------------------------ internals
    def _reset(self) -> None:
        self.bus_up = False
        self.connected.clear()
        self._readings_serial += 1
        self.initialized = False
        self.transaction = None
        self._readings.clear()
        self._board_bits.clear()
        self._last_rx.clear()
        self._lost.clear()
        self._loss_until.clear()
        self._counters.clear()
        self._ticks.clear()
        self._setpoints = dict.fromkeys(MOTORS, 0)
        self._was_emergency = False

    def _start(self, kind: Literal["connect", "init"], now: float, timeout: float, nodes: set[Node]) -> Transaction:
        self._sequence = (self._sequence + 1) & 0xFF
        txn = Transaction(kind, now, now + timeout, self._sequence, nodes)
        self.transaction = txn
        return txn

    def _require(self) -> None:
        if not self.bus_up:
            raise ControllerError("CAN bus not connected")

    def _send(self, node: Node, function: str, signals: dict[str, Any], now: float) -> None:
        self.port.send(candb.build(candb.message_for(node, function), signals, now), now)

    def _receive(self, frame: can.Message, now: float, events: list[HwEvent]) -> None:
        if frame.is_error_frame:
            if frame.arbitration_id & CAN_ERR_BUSOFF:
                self._error_bus_off = True
            if frame.arbitration_id & CAN_ERR_RESTARTED:
                self._error_bus_off = False
            return
        can_id = frame.arbitration_id
        if can_id in self.listening and not frame.is_extended_id:
            stamp = frame.timestamp if self.stamp == "frame" else now
            self._buffer.append(CanRecord(stamp, can_id, bytes(frame.data).ljust(8, b"\0")[:8]))
        entry = self._rx.get(can_id)
        if entry is None or frame.is_remote_frame:
            return
        node, function, msg = entry
        signals = candb.decode(msg, frame)
        if signals is None:
            return
        if function in ANSWERS:
            self._answer(node, function, signals, now)
        if node not in self.connected:
            return
        self._readings.setdefault(node, {})[function] = signals
        self._readings_serial += 1
        if "Status" in signals:
            self._board_bits[node] = int(signals["Status"])
        self._last_rx[node] = now
        if node in self._lost:
            self._lost.discard(node)
            events.append(HwEvent("node_back", node, f"CAN node {node.name} answers again"))
        if function == "Encoder":
            self._encoder(node, signals, now, events)

    def _answer(self, node: Node, function: str, signals: dict[str, Any], now: float) -> None:
        txn = self.transaction
        if txn is None or txn.done or node not in txn.pending or ANSWERS[function] != txn.kind:
            return
        if signals["Sequence"] != txn.sequence:
            return
        txn.pending.discard(node)
        txn.answers[node] = signals
        if txn.kind == "connect":
            self.connected.add(node)
            self._readings_serial += 1
        elif signals["Passed"] and node in MOTORS:
            self._send(node, "Brake", {"Release": 1}, now)  # erratum E-HW-005

    def _encoder(self, node: Node, signals: dict[str, Any], now: float, events: list[HwEvent]) -> None:
        counter = int(signals["Counter"])
        last = self._counters.get(node)
        self._counters[node] = counter
        if last is not None and (gap := (counter - last - 1) & 0xFF):
            self.frames_lost[node] += gap
            if self._loss_until.get(node, -math.inf) <= now:
                events.append(HwEvent("frames_lost", node, f"CAN node {node.name}: {gap} encoder frame(s) lost"))
            self._loss_until[node] = now + FRAME_LOSS_HOLD
        ticks = int(signals["Ticks"])
        previous = self._ticks.get(node)
        self._ticks[node] = ticks
        if previous is not None:
            delta = (ticks - previous + (1 << 31)) % (1 << 32) - (1 << 31)
            radius = float(self.params("RadiusWheel")) if self.params else DEFAULT_RADIUS
            self._travel[node] += delta * 2 * math.pi * radius / self.ticks_per_rev

    def _check_bus_off(self, events: list[HwEvent]) -> None:
        off = self.bus_off
        if off != self._was_bus_off:
            self._was_bus_off = off
            events.append(
                HwEvent(
                    "bus_off" if off else "bus_on",
                    None,
                    "CAN interface bus-off" if off else "CAN interface back on the bus",
                )
            )

    def _check_timeouts(self, now: float, events: list[HwEvent]) -> None:
        for node in sorted(self.connected - self._lost):
            if now - self._last_rx.get(node, now) > NODE_TIMEOUT:
                self._lost.add(node)
                events.append(HwEvent("node_lost", node, f"CAN node {node.name}: no frame for {NODE_TIMEOUT} s"))

    def _check_transaction(self, now: float, events: list[HwEvent]) -> None:
        txn = self.transaction
        if txn is None or txn.done or (txn.pending and now < txn.deadline):
            return
        txn.finished_at = now
        if txn.kind == "init":
            self.initialized = True
            failed = [f"{r.node.name} (errors 0x{r.errors:X})" for r in txn.results.values() if not r.passed]
            text = "self test passed" if not failed else "self test failed: " + ", ".join(failed)
            events.append(HwEvent("init_done", None, text))
        else:
            text = (
                "all CAN nodes answer"
                if not txn.pending
                else "CAN nodes missing: " + ", ".join(n.name for n in txn.missing)
            )
            events.append(HwEvent("connect_done", None, text))

    def _check_emergency(self, events: list[HwEvent]) -> None:
        active = self.emergency_active
        if active == self._was_emergency:
            return
        self._was_emergency = active
        if active:
            self._setpoints = dict.fromkeys(MOTORS, 0)  # no motion until the reset, whatever the server says
            events.append(HwEvent("emergency_pressed", None, "emergency stop: safety circuit open"))
        else:
            events.append(HwEvent("emergency_released", None, "emergency stop: safety circuit reset"))


def _int16(v: float) -> int:
    return max(-32768, min(32767, round(v)))


def _check_id(can_id: int) -> None:
    if not 0 <= can_id <= 0x7FF:
        raise ControllerError(f"CAN id {can_id} is not an 11-bit identifier (E-CMD-006)")
