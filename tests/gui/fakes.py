"""Misbehaving platforms for the fault tests: each accepts on 127.0.0.1 and then does one wrong thing."""

from __future__ import annotations

import contextlib
import socket
import threading
from collections.abc import Iterator

from pltf.spec.codec import encode
from tests.clients.client_fakes import status_telegram


class BadPlatform:
    """``silent``: reads and never answers; ``garbage``: answers anything with bytes that are no frame;
    ``drop``: answers the first request with a status telegram, then closes the connection."""

    def __init__(self, behaviour: str) -> None:
        self.behaviour = behaviour
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port: int = self.listener.getsockname()[1]
        self.conns: list[socket.socket] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._accept, daemon=True)
        self._thread.start()

    @property
    def target(self) -> str:
        return f"127.0.0.1:{self.port}"

    def _accept(self) -> None:
        self.listener.settimeout(0.05)
        while not self._stop.is_set():
            try:
                conn, _ = self.listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            self.conns.append(conn)
            threading.Thread(target=self._serve, args=(conn,), daemon=True).start()

    def _serve(self, conn: socket.socket) -> None:
        with conn:
            while not self._stop.is_set():
                try:
                    data = conn.recv(65536)
                except OSError:
                    return
                if not data:
                    return
                if self.behaviour == "garbage":
                    conn.sendall(b"this is no PlatformCtrl frame")
                elif self.behaviour == "drop":
                    conn.sendall(encode(status_telegram()))
                    return

    def close(self) -> None:
        self._stop.set()
        for c in self.conns:
            with contextlib.suppress(OSError):
                c.shutdown(socket.SHUT_RDWR)
        self.listener.close()
        self._thread.join(5)


@contextlib.contextmanager
def bad_platform(behaviour: str) -> Iterator[BadPlatform]:
    p = BadPlatform(behaviour)
    try:
        yield p
    finally:
        p.close()


def free_port() -> int:
    """A port nothing listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])
