"""Tiny in-test targets for the framework's own tests (no reference server needed).

``ScriptedServer`` runs a handler per connection on 127.0.0.1:0; ``TinyTarget`` is a minimal PlatformCtrl: the
state chart of conformance_tests.chart, CMD_SET_MODE, CMD_GET_STATUS and CMD_GET_POSITION, one client per
port, malformed input closes the connection; every other command is accepted silently.
"""

from __future__ import annotations

import contextlib
import socket
import threading
from collections.abc import Callable
from typing import Any

from conformance_tests import chart
from conformance_tests.chart import St
from conformance_tests.readings import canonical
from spec.codec import REPLIES, TelegramDecoder, encode
from spec.errors import RemoteProtocolError

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
                return self.status.replace(operation_state=chart.REPORTED[self.state],
                                           initialized=chart.INITIALIZED[self.state], motion_mode=self.mode)
            if t.NAME == "CMD_GET_POSITION":
                return REPLIES.CMD_GET_POSITION(x=0, y=0, angle=0.0, vel_trans=0.0, vel_rot=0.0)
            if t.NAME in chart.CHART_COMMANDS and chart.allowed(self.state, t.NAME):
                if t.NAME == "CMD_SET_MODE":
                    self.mode = t.mode
                self.state = chart.target(self.state, t.NAME)
            return None
