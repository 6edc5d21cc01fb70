"""Tiny in-test targets for the framework's own tests (no reference server needed).

``ScriptedServer`` runs a handler per connection on 127.0.0.1:0; ``TinyTarget`` is a minimal PlatformCtrl: the
state chart of conformance_tests.chart, CMD_SET_MODE, CMD_GET_STATUS and CMD_GET_POSITION, one client per
port, malformed input closes the connection; every other command is accepted silently. ``HardwareTarget`` adds
the hardware of the hardware cases, with switchable faults.
"""

from __future__ import annotations

import contextlib
import random
import socket
import threading
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from typing import Any

from pltf.conformance_tests import chart
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.readings import canonical
from pltf.spec.codec import REPLIES, TelegramDecoder, encode
from pltf.spec.errors import RemoteProtocolError
from pltf.spec.parameters import ParameterError, ParameterStore

Handler = Callable[[socket.socket], None]


class ScriptedServer:
    def __init__(self, handler: Handler, ports: int = 1) -> None:
        self.handler = handler
        self._listeners: list[socket.socket] = []
        self.ports: list[int] = []
        self._stop = threading.Event()
        for _ in range(ports):
            ls = socket.socket()
            ls.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            ls.bind(("127.0.0.1", 0))
            ls.listen(8)
            self._listeners.append(ls)
            self.ports.append(ls.getsockname()[1])

    def __enter__(self) -> ScriptedServer:
        for i, ls in enumerate(self._listeners):
            threading.Thread(target=self._accept, args=(ls, i), daemon=True).start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        for ls in self._listeners:
            ls.close()

    def _accept(self, ls: socket.socket, index: int) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = ls.accept()
            except OSError:
                return
            threading.Thread(target=self._run, args=(conn, index), daemon=True).start()

    def _run(self, conn: socket.socket, index: int) -> None:
        with contextlib.closing(conn), contextlib.suppress(OSError):
            self.handler(conn)


def base_status() -> Any:
    """A valid GET_STATUS reply: every field 0, every group empty."""
    return canonical("CMD_GET_STATUS", {})


class TinyTarget(ScriptedServer):
    def __init__(self, ports: int = 2) -> None:
        super().__init__(self._serve, ports)
        self.state = St.NOT_CONNECTED
        self.mode = 0
        self.busy: set[int] = set()
        self.lock = threading.Lock()
        self.status = base_status()
        self.commands: list[str] = []

    def _run(self, conn: socket.socket, index: int) -> None:
        with self.lock:
            if index in self.busy:
                conn.close()
                return
            self.busy.add(index)
        try:
            super()._run(conn, index)
        finally:
            with self.lock:
                self.busy.discard(index)

    def _serve(self, conn: socket.socket) -> None:
        dec = TelegramDecoder("request")
        while True:
            data = conn.recv(65536)
            dec.receive_data(data)
            try:
                for t in dec:
                    reply = self.handle(t)
                    if reply is not None:
                        conn.sendall(encode(reply))
            except RemoteProtocolError:
                return
            if not data:
                return

    def handle(self, t: Any) -> Any:
        with self.lock:
            self.commands.append(t.NAME)
            if t.NAME == "CMD_GET_STATUS":
                return self.status.replace(
                    operation_state=chart.REPORTED[self.state],
                    initialized=chart.INITIALIZED[self.state],
                    motion_mode=self.mode,
                )
            if t.NAME == "CMD_GET_POSITION":
                return REPLIES.CMD_GET_POSITION(x=0, y=0, angle=0.0, vel_trans=0.0, vel_rot=0.0)
            if t.NAME in chart.CHART_COMMANDS and chart.allowed(self.state, t.NAME):
                if t.NAME == "CMD_SET_MODE":
                    self.mode = t.mode
                self.state = chart.target(self.state, t.NAME)
            return None


class LinkTarget(TinyTarget):
    """TinyTarget behind a slow link: it answers once the client's requests pause (``quiet`` s without data), all
    the replies due in one piece, its first eight writes 1-7 bytes, 1 ms apart (coalesced and torn, as the zoo's
    slow-link member). ``reorder`` sends the replies due together last first (a target that breaks E-WIRE-008);
    ``slow_init`` lets CMD_INIT_PLTF take effect only after the status that follows it (a self test that takes a
    while). ``writes`` counts the pieces of replies sent."""

    def __init__(self, *, reorder: bool = False, slow_init: bool = False, quiet: float = 0.02) -> None:
        super().__init__()
        self.reorder, self.slow_init, self.quiet = reorder, slow_init, quiet
        self.rng = random.Random(1)
        self.writes = 0
        self._initializing = False

    def _serve(self, conn: socket.socket) -> None:
        dec = TelegramDecoder("request")
        held: list[bytes] = []
        conn.settimeout(self.quiet)
        while not self._stop.is_set():
            try:
                data = conn.recv(65536)
            except TimeoutError:
                self._flush(conn, held)
                held = []
                continue
            if not data:
                return
            dec.receive_data(data)
            try:
                held += [encode(r) for r in map(self.handle, dec) if r is not None]
            except RemoteProtocolError:
                return

    def _flush(self, conn: socket.socket, held: list[bytes]) -> None:
        data = b"".join(reversed(held) if self.reorder else held)
        for _ in range(8):
            if not data:
                return
            n = self.rng.randint(1, 7)
            conn.sendall(data[:n])
            data = data[n:]
            self.writes += 1
            time.sleep(0.001)
        if data:
            conn.sendall(data)
            self.writes += 1

    def handle(self, t: Any) -> Any:
        if self.slow_init and t.NAME == "CMD_INIT_PLTF" and self.state is St.CONNECTED:
            with self.lock:
                self.commands.append(t.NAME)
                self._initializing = True
            return None
        reply = super().handle(t)
        if self._initializing and t.NAME == "CMD_GET_STATUS":
            with self.lock:
                self.state, self._initializing = St.READY, False
        return reply


class HardwareTarget(TinyTarget):
    """TinyTarget plus the hardware of the hardware cases: a CAN bus with traffic, IO outputs, an
    ultrasonic board, a head drive, parameters, documents and a minimal task interpreter (parameter/set and
    wait/delay). ``broken`` names faults, so the cases that need this hardware can be shown to pass and to fail."""

    BUS_IDS = (0x100, 0x181, 0x205)

    def __init__(self, broken: frozenset[str] = frozenset(), time_scale: float = 10.0) -> None:
        super().__init__()
        self.broken = broken
        self.scale = time_scale
        self.t0 = time.monotonic()
        self.params = ParameterStore()
        self.listening: set[int] = set()
        self.buffer: list[tuple[float, int, tuple[int, ...]]] = []
        self.dout = 0
        self.us = [0] * 16
        self.head = 0
        self.docs: dict[str, tuple[str, str]] = {"map": ("", ""), "roadmap": ("", ""), "program": ("", "")}
        self._going = threading.Event()
        self._aborted = threading.Event()

    def __enter__(self) -> HardwareTarget:
        super().__enter__()
        threading.Thread(target=self._bus, daemon=True).start()
        return self

    def now(self) -> float:
        return (time.monotonic() - self.t0) * self.scale

    def _bus(self) -> None:
        n = 0
        while not self._stop.is_set():
            time.sleep(0.005)
            n += 1
            with self.lock:
                for cid in self.BUS_IDS:
                    if cid in self.listening or "can-all-ids" in self.broken:
                        stamp = -self.now() if "can-time-backwards" in self.broken else self.now()
                        self.buffer.append((stamp, cid, (n % 256,) + (0,) * 7))
                del self.buffer[:-2000]

    def handle(self, t: Any) -> Any:
        name = t.NAME
        if name in chart.CHART_COMMANDS or name in ("CMD_GET_POSITION",):
            if name == "CMD_START" and self.mode == 5 and chart.allowed(self.state, name):
                self._start_program()
            if name == "CMD_BREAK" and "program-ignores-break" not in self.broken:
                self._going.clear()
            if name == "CMD_CONTINUE":
                self._going.set()
            if name in ("CMD_STOP", "CMD_SHUTDOWN_PLTF") and "program-ignores-stop" not in self.broken:
                self._aborted.set()
                self._going.set()
            return super().handle(t)
        with self.lock:
            return self._extra(t)

    def _extra(self, t: Any) -> Any:
        """The commands the fake answers beyond the base: one ``_on_<command>`` method each (None: no reply)."""
        name = t.NAME
        if name in ("CMD_SET_MAP", "CMD_SET_ROADMAP", "CMD_SET_PROGRAM"):
            self.docs[name.split("_", 2)[2].lower()] = (t.xml, getattr(t, "name", ""))
            return None
        if name in ("CMD_GET_MAP", "CMD_GET_ROADMAP"):
            xml, doc_name = self.docs[name.split("_", 2)[2].lower()]
            return REPLIES[name](xml=xml, name=doc_name)
        handler = getattr(self, "_on_" + name, None)
        return handler(t) if handler is not None else None

    def _on_CMD_GET_STATUS(self, t: Any) -> Any:
        return self.status.replace(
            operation_state=chart.REPORTED[self.state],
            motion_mode=self.mode,
            initialized=chart.INITIALIZED[self.state],
            io_digital_out=self.dout,
            us_distance=tuple(self.us),
            head_position=self.head,
        )

    def _on_CMD_ADD_CAN_LISTENING_ID(self, t: Any) -> None:
        self.listening.add(t.can_id)

    def _on_CMD_REMOVE_CAN_LISTENING_ID(self, t: Any) -> None:
        if "can-ignores-remove" not in self.broken:
            self.listening.discard(t.can_id)
            self.buffer = [m for m in self.buffer if m[1] != t.can_id]

    def _on_CMD_GET_CAN_MESSAGES(self, t: Any) -> Any:
        msgs = tuple(self.buffer)
        if t.delete or "can-keep-deletes" in self.broken:
            self.buffer.clear()
        return REPLIES.CMD_GET_CAN_MESSAGES(messages=msgs)

    def _on_CMD_SET_DIGOUT(self, t: Any) -> None:
        if t.board == 0:
            bit = 1 << (t.channel + (1 if "digout-off-by-one" in self.broken else 0))
            self.dout = self.dout | bit if t.value else self.dout & ~bit

    def _on_CMD_START_ULTRASONIC(self, t: Any) -> None:
        if "us-none" not in self.broken:
            self.us = [1500 if t.active_channels >> i & 1 else 0 for i in range(16)]

    def _on_CMD_STOP_ULTRASONIC(self, t: Any) -> None:
        self.us = [0] * 16

    def _on_CMD_SET_POS_HEAD_DRIVE(self, t: Any) -> None:
        self.head = t.angle + (10 if "head-off" in self.broken else 0)

    def _on_CMD_SET_PLTF_PARAM(self, t: Any) -> None:
        with contextlib.suppress(ParameterError):
            self.params.set_text(t.key, t.value)

    def _on_CMD_GET_PLTF_PARAM(self, t: Any) -> Any:
        row = self.params.parameter(t.key)
        lo, hi = row.wire_bounds()
        return REPLIES.CMD_GET_PLTF_PARAM(
            key=t.key,
            value=self.params.get_text(t.key),
            category=row.category,
            data_type=row.type,
            minimum=lo,
            maximum=hi,
        )

    def _on_CMD_GET_PLTF_PARAM_VEC(self, t: Any) -> Any:
        return REPLIES.CMD_GET_PLTF_PARAM_VEC(
            parameters=tuple(
                (row.name, self.params.get_text(row.name), row.category, row.type, *row.wire_bounds())
                for row, _ in self.params.items()
            )
        )

    def _on_CMD_GET_PROGRAM(self, t: Any) -> Any:
        return REPLIES.CMD_GET_PROGRAM(xml=self.docs["program"][0])

    # ---- the task interpreter (MODE_MOTION_PROGRAM)
    def _start_program(self) -> None:
        self._aborted.clear()
        self._going.set()
        root = ET.fromstring(self.docs["program"][0].encode("latin-1"))
        threading.Thread(target=self._program, args=(list(root.iter("task"))[:1],), daemon=True).start()

    def _program(self, tasks: list[ET.Element]) -> None:
        for step in (s for task in tasks for s in task):
            if not self._gate():
                return
            if step.tag == "parameter":
                for s in step.iter("set"):
                    with self.lock, contextlib.suppress(ParameterError):
                        self.params.set_text(s.get("key", ""), s.get("value", ""))
            elif step.tag == "wait" and "program-ignores-delay" not in self.broken:
                for d in step.iter("delay"):
                    end = self.now() + float(d.get("amount", "0")) / 1000.0
                    while self.now() < end:
                        if not self._gate():
                            return
                        time.sleep(0.002)

    def _gate(self) -> bool:
        """Wait while paused (Breaked); False once aborted."""
        self._going.wait()
        return not self._aborted.is_set()
