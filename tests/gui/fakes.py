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


class HeldReplies:
    """A relay in front of a platform that passes every request on at once and holds the platform's replies back
    until ``release()``: the GUI is connected, but its first GET_MAP and GET_ROADMAP are still unanswered."""

    def __init__(self, upstream_port: int) -> None:
        self.upstream_port = upstream_port
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port: int = self.listener.getsockname()[1]
        self.released = threading.Event()
        self._stop = threading.Event()
        self._socks: list[socket.socket] = []
        self._thread = threading.Thread(target=self._accept, daemon=True)
        self._thread.start()

    @property
    def target(self) -> str:
        return f"127.0.0.1:{self.port}"

    def release(self) -> None:
        self.released.set()

    def _accept(self) -> None:
        self.listener.settimeout(0.05)
        while not self._stop.is_set():
            try:
                client, _ = self.listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            self._socks.append(client)
            try:
                upstream = socket.create_connection(("127.0.0.1", self.upstream_port), timeout=5)
            except OSError:
                client.close()
                continue
            upstream.settimeout(None)
            client.settimeout(None)
            self._socks.append(upstream)
            threading.Thread(target=self._pump, args=(client, upstream, False), daemon=True).start()
            threading.Thread(target=self._pump, args=(upstream, client, True), daemon=True).start()

    def _pump(self, src: socket.socket, dst: socket.socket, held: bool) -> None:
        with contextlib.suppress(OSError):
            while data := src.recv(65536):
                if held:
                    self.released.wait()
                dst.sendall(data)
        with contextlib.suppress(OSError):
            dst.shutdown(socket.SHUT_WR)

    def close(self) -> None:
        self._stop.set()
        self.released.set()
        self._thread.join(5)
        self.listener.close()
        for s in self._socks:
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)
            s.close()


@contextlib.contextmanager
def bad_platform(behaviour: str) -> Iterator[BadPlatform]:
    p = BadPlatform(behaviour)
    try:
        yield p
    finally:
        p.close()


@contextlib.contextmanager
def held_replies(upstream_port: int) -> Iterator[HeldReplies]:
    relay = HeldReplies(upstream_port)
    try:
        yield relay
    finally:
        relay.close()


def free_port() -> int:
    """A port nothing listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])
