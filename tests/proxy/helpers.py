"""Test helpers of the proxy: the proxy in a thread of its own (its asyncio loop), a raw TCP peer, a client."""

from __future__ import annotations

import asyncio
import contextlib
import socket
import threading
import time
from typing import Any

from pltf.proxy.network import ProxyServer, Route
from pltf.proxy.recorder import Recorder
from pltf.proxy.tap import Record


class ProxyThread:
    """``ProxyServer`` on 127.0.0.1 ephemeral ports, one per target port, recording into ``records``."""

    threads = False  # the forwarding core: Python threads (True) or the C loop (tests/proxy/test_network.py runs both)

    def __init__(self, target_ports: list[int], recorder: Recorder | None = None, host: str = "127.0.0.1") -> None:
        self.records: list[Record] = []
        self.recorder = recorder or Recorder([self.records.append])
        self.routes = [Route("127.0.0.1", 0, host, p) for p in target_ports]
        self.ports: list[int] = []
        self.server: ProxyServer | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._ready = threading.Event()
        self._thread = threading.Thread(target=lambda: asyncio.run(self._main()), daemon=True, name="proxy")
        self.error: BaseException | None = None

    async def _main(self) -> None:
        try:
            self.server = ProxyServer(self.routes, self.recorder, threads=self.threads)
            self._loop = asyncio.get_running_loop()
            self.ports = [p for _, p in await self.server.start()]
            self._ready.set()
            await self.server.wait_stopped()
            await self.server.close()
        except BaseException as exc:
            self.error = exc
            raise
        finally:
            self._ready.set()

    def start(self) -> ProxyThread:
        self._thread.start()
        self._ready.wait(10)
        assert self.ports, f"the proxy did not start: {self.error!r}"
        return self

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()

    def stop(self) -> None:
        if self._loop is not None and self.server is not None and self._thread.is_alive():
            self._loop.call_soon_threadsafe(self.server.request_stop)
        self._thread.join(10)

    def __enter__(self) -> ProxyThread:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def wait_records(self, predicate: Any, timeout: float = 5.0) -> list[Record]:
        deadline = time.monotonic() + timeout
        while not predicate(self.records):
            seen = [f"{r.kind}:{r.name}:{r.detail}" for r in self.records[-8:]]
            assert time.monotonic() < deadline, f"records never matched; the last: {seen}"
            time.sleep(0.01)
        return self.records


class Peer:
    """A raw TCP server for one connection at a time: keeps what it reads, sends what it is told."""

    def __init__(self) -> None:
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port: int = self.sock.getsockname()[1]
        self.conn: socket.socket | None = None
        self.received = bytearray()
        self.eof = threading.Event()
        self._accepted = threading.Event()
        self._reading = True
        self._thread = threading.Thread(target=self._serve, daemon=True, name="peer")
        self._thread.start()

    def _serve(self) -> None:
        try:
            conn, _ = self.sock.accept()
        except OSError:
            return
        self.conn = conn
        self._accepted.set()
        while self._reading:
            try:
                data = conn.recv(65536)
            except OSError:
                break
            if not data:
                break
            self.received += data
        self.eof.set()

    def accepted(self, timeout: float = 5.0) -> socket.socket:
        assert self._accepted.wait(timeout), "the proxy never connected to the peer"
        assert self.conn is not None
        return self.conn

    def wait_bytes(self, n: int, timeout: float = 5.0) -> bytes:
        deadline = time.monotonic() + timeout
        while len(self.received) < n:
            assert time.monotonic() < deadline, f"peer got {len(self.received)} of {n} bytes"
            time.sleep(0.005)
        return bytes(self.received)

    def close(self) -> None:
        self._reading = False
        for s in (self.conn, self.sock):
            if s is not None:
                with contextlib.suppress(OSError):
                    s.close()
        self._thread.join(5)


def read_exactly(sock: socket.socket, n: int, timeout: float = 5.0) -> bytes:
    sock.settimeout(timeout)
    out = bytearray()
    while len(out) < n:
        data = sock.recv(n - len(out))
        if not data:
            break
        out += data
    return bytes(out)


def read_to_end(sock: socket.socket, timeout: float = 5.0) -> bytes:
    sock.settimeout(timeout)
    out = bytearray()
    while data := sock.recv(65536):
        out += data
    return bytes(out)
