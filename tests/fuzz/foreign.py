"""Foreign targets for the fuzzer's tests: an implementation (the reference server by default) behind a small TCP
proxy that behaves as implementations we did not write do.

``python tests/fuzz/foreign.py --ports 0,0 [--release 5-50] [--turn-away fin|rst|refuse] [--accept-once]
[--bug NAME] [--backend CMD]`` listens on 127.0.0.1 and prints ``server started at port N`` per port (the
reference server's convention, which ``pltf.fuzz.launch`` reads); each client gets its own connection to the
backend, which the proxy starts on free ports of its own and stops when it ends (or dies).

Behaviours (each conforming: one client per port, erratum E-WIRE-007 and its alternative reading):
- ``--release MIN-MAX`` (ms): after a client has left, the port is freed only MIN-MAX ms later (a random delay
  each time); until then a newcomer is turned away (``--turn-away``: ``fin`` accepted and closed, ``rst``
  accepted and reset, ``refuse`` the listener closed: connection refused). A newcomer on a busy port too.
- ``--accept-once``: a newcomer is not accepted while the port serves a client: it waits in the listen backlog.

Planted bugs (``--bug``), each a classic slip of a C++ controller; the proxy watches the requests it forwards and
follows the state chart (guide 4.2) from the chart commands:
- ``move-crash``: initialised and started (Running), then CMD_MOVE_REL with |x| or |y| >= 2^30: the process dies.
- ``vel-crash``: motion mode VEL and Running, then CMD_MOVE_VEL_WHEEL with a wheel velocity <= -2^30: dies.
- ``hang``: CMD_SET_PLTF_PARAM whose value starts with "nan" or "inf": the whole process stops (no accept, no
  reply, on both ports) for ``HANG_SECONDS``.
- ``leak``: every document sent (CMD_SET_MAP, CMD_SET_ROADMAP, CMD_SET_PROGRAM) leaks its size; past
  ``--leak-limit-mb`` the process dies as the out-of-memory killer would end it.

``--stats FILE`` writes the clients served and turned away per port at exit (SIGTERM), as JSON.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import json
import os
import random
import selectors
import shlex
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time

HEADER = b"\xff\x01\xfe\x02"
HANG_SECONDS = 60.0
READ = 1 << 16
HIGH_WATER = 4 << 20  # bytes buffered one way before reading that side pauses
REFERENCE = (
    f"{sys.executable} -m pltf.reference_server --ports {{ports}} --data-dir {{tmpdir}} --seed 1 --log-level ERROR"
)
# guide 6.3 ids of the chart commands and the bugs' telegrams (spec/telegrams.yaml)
CONNECT, SHUTDOWN, INIT, START, BREAK, CONTINUE, STOP, SET_MODE = 0, 1, 2, 11, 12, 13, 14, 15
MOVE_REL, MOVE_VEL_WHEEL, SET_PLTF_PARAM, DOCUMENTS = 22, 23, 37, frozenset({25, 32, 40})
MODE_VEL = 3
# (state, command) -> next state: the chart of guide 4.2 figure 2 as conformance_tests/chart.py reads it
CHART = {
    ("not_connected", CONNECT): "connected",
    ("connected", INIT): "ready",
    ("ready", START): "running",
    ("running", BREAK): "breaked",
    ("breaked", CONTINUE): "running",
    ("running", STOP): "ready",
    ("breaked", STOP): "ready",
    **{(s, SHUTDOWN): "not_connected" for s in ("connected", "ready", "running", "breaked")},
}
BIG = 1 << 30


def _i32(data: bytes, at: int) -> int:
    return struct.unpack_from(">i", data, at)[0] if len(data) >= at + 4 else 0


class Platform:
    """What the planted bugs look at: the chart state and mode, and the memory leaked so far."""

    def __init__(self, bug: str, leak_limit: int, backend: Backend) -> None:
        self.bug, self.leak_limit, self.backend = bug, leak_limit, backend
        self.state, self.mode = "not_connected", 0
        self.leaked: list[int] = []

    def frame(self, ident: int, size: int, head: bytes) -> None:
        """A whole request frame: its id, its data size and the first bytes of its data (id first)."""
        if ident == SET_MODE and self.state == "ready" and size == 5:
            self.mode = _i32(head, 1)
        elif size == 1:
            self.state = CHART.get((self.state, ident), self.state)
        running = self.state == "running"
        far = max(abs(_i32(head, 1)), abs(_i32(head, 5))) >= BIG
        if self.bug == "move-crash" and ident == MOVE_REL and running and far:
            self.crash(134, "CMD_MOVE_REL far out while running")
        vel = running and self.mode == MODE_VEL
        if self.bug == "vel-crash" and ident == MOVE_VEL_WHEEL and vel and min(_i32(head, 1), _i32(head, 5)) <= -BIG:
            self.crash(134, "CMD_MOVE_VEL_WHEEL with a huge negative velocity in mode VEL")
        if self.bug == "hang" and ident == SET_PLTF_PARAM and len(head) >= 5:
            n = _i32(head, 1)
            value_at = 5 + n + 4
            if n >= 0 and value_at <= len(head) and head[value_at : value_at + 3].lower() in (b"nan", b"inf"):
                print("foreign target: hanging on a parameter value", flush=True)
                time.sleep(HANG_SECONDS)
        if self.bug == "leak" and ident in DOCUMENTS:
            self.leaked.append(size)
            if sum(self.leaked) > self.leak_limit:
                self.crash(137, f"out of memory after {len(self.leaked)} documents")

    def crash(self, code: int, why: str) -> None:
        print(f"foreign target: crashing on {why}", flush=True)
        self.backend.kill()
        os._exit(code)


class Frames:
    """Frames of a client's stream as they pass: the id, size and first ``HEAD`` bytes of each, to the platform."""

    HEAD = 4200  # enough for a parameter key and the start of its value

    def __init__(self, platform: Platform) -> None:
        self.platform, self.buf, self.skip, self.broken = platform, b"", 0, False

    def feed(self, data: bytes) -> None:
        if self.broken:
            return
        if self.skip:
            cut = min(self.skip, len(data))
            self.skip -= cut
            data = data[cut:]
        self.buf += data
        while len(self.buf) >= 8:
            if self.buf[:4] != HEADER:
                self.broken = True  # the backend closes this connection; nothing more to follow
                return
            (n,) = struct.unpack_from(">I", self.buf, 4)
            if n == 0 or n > 64 << 20:
                self.broken = True
                return
            if len(self.buf) < 8 + min(n, self.HEAD):
                return
            head = self.buf[8 : 8 + min(n, self.HEAD)]
            self.platform.frame(head[0], n, head)
            have = len(self.buf) - 8
            if have >= n:
                self.buf = self.buf[8 + n :]
            else:
                self.buf, self.skip = b"", n - have


class Backend:
    """The implementation behind the proxy, on free ports; it dies with us (PR_SET_PDEATHSIG)."""

    def __init__(self, template: str) -> None:
        self.tmp = tempfile.mkdtemp(prefix="pltf-foreign-")
        self.ports = free_ports()
        cmd = shlex.split(template.format(ports=f"{self.ports[0]},{self.ports[1]}", tmpdir=self.tmp))
        self.proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, preexec_fn=_die_with_parent)  # noqa: PLW1509
        deadline = time.monotonic() + 30
        for port in self.ports:
            while True:
                try:
                    socket.create_connection(("127.0.0.1", port), timeout=1).close()
                    break
                except OSError:
                    if self.proc.poll() is not None or time.monotonic() > deadline:
                        sys.exit(f"foreign target: the backend did not start ({cmd[0]})")
                    time.sleep(0.05)

    def kill(self) -> None:
        with contextlib.suppress(OSError):
            self.proc.kill()
        self.proc.wait()
        shutil.rmtree(self.tmp, ignore_errors=True)


def _die_with_parent() -> None:
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG


def free_ports() -> tuple[int, int]:
    socks = [socket.socket() for _ in range(2)]
    for s in socks:
        s.bind(("127.0.0.1", 0))
    ports = (socks[0].getsockname()[1], socks[1].getsockname()[1])
    for s in socks:
        s.close()
    return ports


class Pair:
    """A client and its own connection to the backend, relayed both ways with half-closes kept."""

    def __init__(self, proxy: Proxy, port: Port, client: socket.socket) -> None:
        self.proxy, self.port, self.client = proxy, port, client
        self.backend = socket.create_connection(("127.0.0.1", proxy.backend.ports[port.index]), timeout=2)
        for s in (client, self.backend):
            s.setblocking(False)
            s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.out = {client: bytearray(), self.backend: bytearray()}  # bytes waiting to be written to that socket
        self.eof = {client: False, self.backend: False}  # end-of-stream read from that socket
        self.frames = Frames(proxy.platform) if proxy.platform.bug != "none" else None
        self.closed = False
        self.events = {client: 0, self.backend: 0}
        for s in (client, self.backend):
            self._want(s, selectors.EVENT_READ)

    def other(self, s: socket.socket) -> socket.socket:
        return self.backend if s is self.client else self.client

    def event(self, s: socket.socket, mask: int) -> None:
        if mask & selectors.EVENT_READ and not self.eof[s]:
            try:
                data = s.recv(READ)
            except BlockingIOError:
                data = None
            except OSError:  # a reset: what it sent before is on its way already
                data = b""
            if data == b"":
                self.eof[s] = True
            elif data:
                if s is self.client and self.frames is not None:
                    self.frames.feed(data)
                self.out[self.other(s)] += data
        if not self.closed:
            self.flush()

    def flush(self) -> None:
        for s in (self.client, self.backend):
            buf = self.out[s]
            try:
                while buf:
                    del buf[: s.send(buf)]
            except BlockingIOError:
                pass
            except OSError:
                self.close()
                return
            if not buf and self.eof[self.other(s)]:
                with contextlib.suppress(OSError):
                    s.shutdown(socket.SHUT_WR)
        if all(self.eof.values()) and not any(self.out.values()):
            self.close()
            return
        for s in (self.client, self.backend):
            events = 0 if self.eof[s] or len(self.out[self.other(s)]) > HIGH_WATER else selectors.EVENT_READ
            events |= selectors.EVENT_WRITE if self.out[s] else 0
            self._want(s, events)

    def _want(self, s: socket.socket, events: int) -> None:
        """Wait for ``events`` on ``s`` (none: not registered)."""
        if events == self.events[s]:
            return
        if not events:
            self.proxy.sel.unregister(s)
        elif not self.events[s]:
            self.proxy.sel.register(s, events, self)
        else:
            self.proxy.sel.modify(s, events, self)
        self.events[s] = events

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        for s in (self.client, self.backend):
            self._want(s, 0)
            s.close()
        self.proxy.left(self.port)


class Port:
    def __init__(self, index: int, port: int) -> None:
        self.index, self.port = index, port
        self.listener: socket.socket | None = None
        self.busy = False
        self.free_at = 0.0
        self.served = self.turned_away = 0


class Proxy:
    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        lo, _, hi = args.release.partition("-")
        self.release = (float(lo) / 1000, float(hi or lo) / 1000)
        self.rng = random.Random(args.seed)
        self.sel = selectors.DefaultSelector()
        self.backend = Backend(args.backend)
        self.platform = Platform(args.bug, int(args.leak_limit_mb * (1 << 20)), self.backend)
        self.ports = [Port(k, int(p)) for k, p in enumerate(args.ports.split(","))]
        for port in self.ports:
            self.listen(port)
            port.port = port.listener.getsockname()[1]  # type: ignore[union-attr]
            print(f"server started at port {port.port}", flush=True)

    def listen(self, port: Port) -> None:
        s = socket.socket()
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind(("127.0.0.1", port.port))
        s.listen(64)
        s.setblocking(False)
        port.listener = s
        self.sel.register(s, selectors.EVENT_READ, port)

    def unlisten(self, port: Port, close: bool) -> None:
        if port.listener is not None:
            with contextlib.suppress(KeyError, ValueError):
                self.sel.unregister(port.listener)
            if close:
                port.listener.close()
                port.listener = None

    def accept(self, port: Port) -> None:
        while port.listener is not None:
            try:
                client, _ = port.listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            if port.busy or time.monotonic() < port.free_at:
                port.turned_away += 1
                if self.args.turn_away == "rst":
                    client.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
                client.close()
                continue
            port.busy = True
            port.served += 1
            try:
                Pair(self, port, client)
            except OSError:  # the backend is gone
                client.close()
                port.busy = False
                continue
            if self.args.accept_once or self.args.turn_away == "refuse":
                self.unlisten(port, close=self.args.turn_away == "refuse" and not self.args.accept_once)
                return

    def left(self, port: Port) -> None:
        """The port's client has gone: the port is free after the release delay."""
        port.busy = False
        port.free_at = time.monotonic() + self.rng.uniform(*self.release)
        if not (self.args.accept_once or self.args.turn_away == "refuse"):
            return
        if port.free_at <= time.monotonic():
            self.reopen(port)

    def reopen(self, port: Port) -> None:
        if port.listener is None:
            self.listen(port)
        else:
            with contextlib.suppress(KeyError):
                self.sel.register(port.listener, selectors.EVENT_READ, port)
        self.accept(port)

    def run(self) -> None:
        while True:
            now = time.monotonic()
            waiting = [p for p in self.ports if not p.busy and p.free_at > 0 and self._closed(p)]
            for p in [p for p in waiting if p.free_at <= now]:
                self.reopen(p)
            timeout = min((p.free_at - now for p in waiting if p.free_at > now), default=None)
            for key, mask in self.sel.select(timeout):
                if isinstance(key.data, Port):
                    self.accept(key.data)
                else:
                    key.data.event(key.fileobj, mask)

    def _closed(self, port: Port) -> bool:
        """Whether the port waits for its release to accept again (accept-once, refuse)."""
        if port.listener is None:
            return True
        try:
            self.sel.get_key(port.listener)
        except KeyError:
            return True
        return False

    def stats(self) -> dict[str, list[int]]:
        return {"served": [p.served for p in self.ports], "turned_away": [p.turned_away for p in self.ports]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ports", default="0,0", help="the proxy's two ports (0: ephemeral)")
    parser.add_argument("--backend", default=REFERENCE, help="the implementation behind ({ports}, {tmpdir})")
    parser.add_argument(
        "--release",
        default="0",
        metavar="MIN-MAX",
        help="ms after a client left until the port takes the next (turned away until then)",
    )
    parser.add_argument("--turn-away", choices=("fin", "rst", "refuse"), default="fin")
    parser.add_argument("--accept-once", action="store_true", help="newcomers wait in the backlog")
    parser.add_argument("--bug", default="none", choices=("none", "move-crash", "vel-crash", "hang", "leak"))
    parser.add_argument("--leak-limit-mb", type=float, default=8.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--stats", help="write the clients served and turned away here at exit (JSON)")
    args = parser.parse_args()
    proxy = Proxy(args)

    def stop(*_: object) -> None:
        if args.stats:
            with open(args.stats, "w") as fh:
                json.dump(proxy.stats(), fh)
        proxy.backend.kill()
        os._exit(0)

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    proxy.run()


if __name__ == "__main__":
    main()
