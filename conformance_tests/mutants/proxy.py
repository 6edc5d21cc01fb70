"""A frame-aware TCP proxy in front of a server's ports: the carrier of the wire-level mutants.

Rules:
- One listening socket per upstream port (ephemeral ports on 127.0.0.1); each client gets its own upstream
  connection on the matching port; two pump threads per client copy the bytes.
- Client -> server bytes are forwarded as they come (so split, slow and malformed input reach the server as the
  suite sent it) unless the mutant asks for whole frames (``Mutant.wants_client_frames``); then complete frames
  go through ``client_frame`` and anything that is not a frame is passed through raw.
- Server -> client bytes are cut into frames (the server frames correctly) and go through ``server_frame``.
- ``mutant`` can be swapped between runs; None is a faithful proxy. The proxy ends only the sockets and threads
  it created.
"""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from pltf.spec.codec import DEFAULT_MAX_LENGTH, HEADER

_LEN = struct.Struct(">I")


@dataclass
class Conn:
    """One proxied client connection (state a mutant may keep per connection)."""

    index: int  # which upstream port (0 or 1)
    client: socket.socket
    upstream: socket.socket | None
    state: dict[str, Any] = field(default_factory=dict)
    closed: threading.Event = field(default_factory=threading.Event)

    def to_client(self, data: bytes) -> None:
        with contextlib.suppress(OSError):
            self.client.sendall(data)

    def to_server(self, data: bytes) -> None:
        if self.upstream is not None:
            with contextlib.suppress(OSError):
                self.upstream.sendall(data)

    def close(self) -> None:
        self.closed.set()
        for s in (self.client, self.upstream):
            if s is not None:
                with contextlib.suppress(OSError):
                    s.shutdown(socket.SHUT_RDWR)
                with contextlib.suppress(OSError):
                    s.close()


def split_frames(buf: bytearray) -> list[bytes]:
    """Take the complete frames off the front of ``buf`` (header + length + data); stops at anything else."""
    out = []
    while len(buf) >= 8 and buf[:4] == HEADER:
        (n,) = _LEN.unpack_from(buf, 4)
        if n > DEFAULT_MAX_LENGTH or len(buf) < 8 + n:
            break
        out.append(bytes(buf[: 8 + n]))
        del buf[: 8 + n]
    return out


class FrameProxy:
    def __init__(self, upstream_host: str, upstream_ports: Sequence[int], mutant: Any = None) -> None:
        self.upstream_host = upstream_host
        self.upstream_ports = list(upstream_ports)
        self.mutant = mutant
        self.ports: list[int] = []
        self.shared: dict[str, Any] = {}
        self._listeners: list[socket.socket] = []
        self._conns: list[Conn] = []
        self.held: list[socket.socket] = []  # client sockets a mutant took over
        self._lock = threading.Lock()
        self._stop = threading.Event()

    def start(self) -> FrameProxy:
        for index in range(len(self.upstream_ports)):
            ls = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            ls.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            ls.bind(("127.0.0.1", 0))
            ls.listen(16)
            self._listeners.append(ls)
            self.ports.append(ls.getsockname()[1])
            threading.Thread(target=self._accept, args=(ls, index), daemon=True, name=f"proxy-accept-{index}").start()
        return self

    def set_mutant(self, mutant: Any) -> None:
        """Swap the mutant; open connections are closed so that every case starts on the new behaviour."""
        self.mutant = mutant
        self.shared.clear()
        while self.held:
            with contextlib.suppress(OSError):
                self.held.pop().close()
        with self._lock:
            conns, self._conns = self._conns, []
        for c in conns:
            c.close()

    def stop(self) -> None:
        self._stop.set()
        for ls in self._listeners:
            with contextlib.suppress(OSError):
                ls.close()
        self.set_mutant(None)

    def __enter__(self) -> FrameProxy:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def close_all(self) -> None:
        with self._lock:
            conns = list(self._conns)
        for c in conns:
            c.close()

    def open_on(self, index: int) -> int:
        with self._lock:
            return sum(1 for c in self._conns if c.index == index and not c.closed.is_set())

    # ---- plumbing
    def _accept(self, ls: socket.socket, index: int) -> None:
        while not self._stop.is_set():
            try:
                client, _ = ls.accept()
            except OSError:
                return
            client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            m = self.mutant
            if m is not None and m.on_accept(self, index, client):
                continue  # the mutant took the connection over
            try:
                up = socket.create_connection((self.upstream_host, self.upstream_ports[index]), timeout=5.0)
                up.settimeout(None)
                up.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            except OSError:
                client.close()
                continue
            conn = Conn(index, client, up)
            with self._lock:
                self._conns.append(conn)
            threading.Thread(target=self._client_to_server, args=(conn, m), daemon=True).start()
            threading.Thread(target=self._server_to_client, args=(conn, m), daemon=True).start()

    def _client_to_server(self, conn: Conn, m: Any) -> None:
        buf = bytearray()
        raw = False
        while True:
            try:
                data = conn.client.recv(65536)
            except OSError:
                data = b""
            if not data:
                if m is not None and m.on_client_eof(self, conn, bytes(buf)):
                    return
                if buf:
                    conn.to_server(bytes(buf))
                if conn.upstream is not None:
                    with contextlib.suppress(OSError):
                        conn.upstream.shutdown(socket.SHUT_WR)
                return
            if m is None or not m.wants_client_frames or raw:
                data = m.client_bytes(self, conn, data) if m is not None else data
                conn.to_server(data)
                continue
            conn.state["recv"] = conn.state.get("recv", 0) + 1
            conn.state["chunks"] = conn.state.get("chunks", 0) + 1
            buf += data
            for frame in split_frames(buf):
                m.client_frame(self, conn, frame)
            conn.state["chunks"] = 1 if buf else 0
            if buf and (
                buf[: min(4, len(buf))] != HEADER[: min(4, len(buf))]
                or (len(buf) >= 8 and _LEN.unpack_from(buf, 4)[0] > DEFAULT_MAX_LENGTH)
            ):
                raw = not m.malformed(self, conn, bytes(buf))
                if raw:
                    conn.to_server(bytes(buf))
                buf.clear()

    def _server_to_client(self, conn: Conn, m: Any) -> None:
        buf = bytearray()
        assert conn.upstream is not None
        while True:
            try:
                data = conn.upstream.recv(65536)
            except OSError:
                data = b""
            if not data:
                conn.close()
                return
            buf += data
            for frame in split_frames(buf):
                if m is None:
                    conn.to_client(frame)
                else:
                    m.server_frame(self, conn, frame)
