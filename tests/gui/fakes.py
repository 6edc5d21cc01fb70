"""Platforms that misbehave for the fault tests, each accepting on 127.0.0.1 and then doing one wrong thing, and a
relay that holds a platform's replies back (``HeldReplies``)."""

from __future__ import annotations

import contextlib
import socket
import threading

from pltf.spec.codec import encode
from tests.clients.client_fakes import LoopbackServer, status_telegram


class _Listening(LoopbackServer):
    @property
    def target(self) -> str:
        """The address the GUI is pointed at (``?target=``)."""
        return f"127.0.0.1:{self.port}"


class BadPlatform(_Listening):
    """``silent``: reads and never answers; ``garbage``: answers anything with bytes that are no frame;
    ``drop``: answers the first request with a status telegram, then closes the connection."""

    def __init__(self, behaviour: str) -> None:
        super().__init__()
        self.behaviour = behaviour
        self.start()

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


class HeldReplies(_Listening):
    """A relay in front of a platform that passes every request on at once and holds the platform's replies back
    until ``release()``: the GUI is connected, but its first GET_MAP and GET_ROADMAP are still unanswered."""

    def __init__(self, upstream_port: int) -> None:
        super().__init__()
        self.upstream_port = upstream_port
        self.released = threading.Event()
        self.start()

    def release(self) -> None:
        self.released.set()

    def _serve(self, client: socket.socket) -> None:
        try:
            upstream = socket.create_connection(("127.0.0.1", self.upstream_port), timeout=5)
        except OSError:
            return
        upstream.settimeout(None)
        self.conns.append(upstream)
        self.spawn(self._pump, upstream, client, True)
        self._pump(client, upstream, False)

    def _pump(self, src: socket.socket, dst: socket.socket, held: bool) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                if held:
                    self.released.wait()
                dst.sendall(data)
        with contextlib.suppress(OSError):
            dst.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self.released.set()
        super().close()


def free_port() -> int:
    """A port nothing listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])
