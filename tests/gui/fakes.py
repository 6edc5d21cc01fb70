"""Platforms that misbehave for the fault tests, each accepting on 127.0.0.1 and then doing one wrong thing, a
relay that holds a platform's replies back (``HeldReplies``), and for the doors tests (issue 33) a platform that
records what reaches it (``Recorder``), a raw HTTP request with any Host and Origin (``request``, ``upgrade``) and
a WebSocket tab that speaks the gateway's protocol as a page's script would, without a browser (``Tab``).

The tabs run on an event loop of their own thread (``run``): Playwright's sync API (tests/gui's browser fixture,
package scope) keeps an event loop marked running in the main thread, where ``asyncio.run`` would refuse to start.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import http.client
import json
import socket
import threading
from collections.abc import Awaitable, Callable
from typing import Any, TypeVar

import aiohttp

from pltf.spec.codec import TelegramDecoder, build, encode
from pltf.spec.errors import RemoteProtocolError
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


class Recorder(_Listening):
    """A platform that records what reaches it: every connection accepted (``connects``) and every request
    telegram's name (``received``), in order; it answers CMD_GET_STATUS with a status telegram and nothing else
    (the doors tests, issue 33: what a refused page must not get to the target)."""

    def __init__(self) -> None:
        super().__init__()
        self.connects = 0
        self.received: list[str] = []
        self.start()

    def _serve(self, conn: socket.socket) -> None:
        self.connects += 1
        decoder = TelegramDecoder("request")
        with conn, contextlib.suppress(OSError):
            while data := conn.recv(65536):
                try:
                    decoder.receive_data(data)
                    while (telegram := decoder.next_telegram()) is not None:
                        self.received.append(telegram.NAME)
                        if telegram.NAME == "CMD_GET_STATUS":
                            conn.sendall(encode(status_telegram()))
                except RemoteProtocolError:
                    self.received.append(f"not a telegram: {data[:40]!r}")
                    return


# ---------------------------------------------------------------- the doors tests' clients (issue 33)
PATIENCE = 30.0  # s: a guard against a hang, not a speed assertion
T = TypeVar("T")

MOVE_VEL = encode(build("request", "CMD_MOVE_VEL", vel_trans=100, vel_rot=0))
GET_STATUS = encode(build("request", "CMD_GET_STATUS"))


def request(port: int, path: str, headers: dict[str, str], method: str = "GET") -> tuple[int, str, Any]:
    """One HTTP request to 127.0.0.1:port with exactly these headers (Host included): (status, body, headers)."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=PATIENCE)
    try:
        conn.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
        for k, v in headers.items():
            conn.putheader(k, v)
        conn.endheaders()
        r = conn.getresponse()
        return r.status, r.read().decode("utf-8", "replace"), r.headers
    finally:
        conn.close()


def upgrade(port: int, target: str, headers: dict[str, str]) -> tuple[int, str, Any]:
    """A WebSocket opening handshake to /ws?target=...: 101 when the gateway lets the tab in."""
    ws = {
        "Upgrade": "websocket",
        "Connection": "Upgrade",
        "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ==",
        "Sec-WebSocket-Version": "13",
    }
    return request(port, f"/ws?target={target}", {**ws, **headers})


def run(make: Callable[[], Awaitable[T]]) -> T:
    """Run ``make()`` to completion on a fresh event loop in a thread of its own."""
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        return pool.submit(lambda: asyncio.run(_bounded(make))).result()


async def _bounded(make: Callable[[], Awaitable[T]]) -> T:
    return await asyncio.wait_for(make(), 4 * PATIENCE)


class Tab:
    """One WebSocket to the gateway, as a page's script would hold it: sends frames and ops, reads events."""

    def __init__(self, http: aiohttp.ClientSession, ws: aiohttp.ClientWebSocketResponse) -> None:
        self.http = http
        self.ws = ws
        self.events: list[dict[str, Any]] = []
        self.frames: list[bytes] = []

    @classmethod
    async def open(cls, base: str, target: str, headers: dict[str, str] | None = None) -> Tab:
        http = aiohttp.ClientSession()
        try:
            ws = await http.ws_connect(f"{base}/ws?target={target}", headers=headers or {})
        except BaseException:
            await http.close()
            raise
        return cls(http, ws)

    async def op(self, op: str, **fields: Any) -> None:
        await self.ws.send_str(json.dumps({"op": op, **fields}))

    async def frame(self, data: bytes) -> None:
        await self.ws.send_bytes(data)

    async def until(self, pred: Callable[[dict[str, Any] | bytes], bool], what: str) -> dict[str, Any] | bytes:
        """Read until a message (an event's dict, or a frame's bytes) satisfies ``pred``; return it."""
        deadline = asyncio.get_running_loop().time() + PATIENCE
        while True:
            left = deadline - asyncio.get_running_loop().time()
            if left <= 0:
                raise AssertionError(f"timed out waiting for {what}; events: {self.events[-6:]}")
            msg = await self.ws.receive(timeout=left)
            if msg.type == aiohttp.WSMsgType.TEXT:
                item: dict[str, Any] | bytes = json.loads(msg.data)
                self.events.append(item)  # type: ignore[arg-type]
            elif msg.type == aiohttp.WSMsgType.BINARY:
                item = bytes(msg.data)
                self.frames.append(item)
            else:
                raise AssertionError(f"the WebSocket ended ({msg.type.name}) while waiting for {what}: {self.events}")
            if pred(item):
                return item

    async def event(self, name: str, **fields: Any) -> dict[str, Any]:
        def match(m: dict[str, Any] | bytes) -> bool:
            return isinstance(m, dict) and m.get("event") == name and all(m.get(k) == v for k, v in fields.items())

        got = await self.until(match, f"event {name} {fields or ''}")
        assert isinstance(got, dict)
        return got

    async def status(self) -> bytes:
        """Send GET_STATUS and wait for its reply: every frame this tab sent before has reached the gateway's
        link (one WebSocket, read in order) and, if it was passed on, the platform (one connection, in order)."""
        await self.frame(GET_STATUS)
        got = await self.until(lambda m: isinstance(m, bytes), "the GET_STATUS reply")
        assert isinstance(got, bytes)
        return got

    async def close(self) -> None:
        await self.ws.close()
        await self.http.close()
