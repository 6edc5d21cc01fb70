"""proxy/network.py over real loopback sockets, with each of its two forwarding cores (the C loop and the Python
threads): bytes pass unchanged both ways however they are cut, garbage included; half-close, reset and an
unreachable target look to the other side as they would without the proxy; a slow reader slows the sender;
nothing that passes through stops the proxy."""

from __future__ import annotations

import contextlib
import random
import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from benchmarks.proc_cpu import TICK, stat_cpu
from pltf.proxy import network
from pltf.proxy.recorder import Recorder
from pltf.proxy.replay import plan
from pltf.proxy.session import Route, Session
from pltf.proxy.tap import CLOSE, FRAME, OPEN, RAW, Record
from pltf.spec.codec import REQUESTS, encode
from tests.proxy.helpers import Peer, ProxyThread, read_exactly, read_to_end

STOP = encode(REQUESTS.CMD_STOP())
SET_MODE = bytes.fromhex("ff01fe02000000050f00000003")
GARBAGE = b"\x00\x01garbage\xff\x01\xfe"


@pytest.fixture(autouse=True, params=["c-loop", "threads"])
def core(request: pytest.FixtureRequest) -> Iterator[str]:
    """Every test runs once with each forwarding core (the C loop is built by ``make``: it must be there)."""
    if request.param == "c-loop":
        assert network.HAVE_C, "proxy/_forward.c is not built (make install builds it)"
    ProxyThread.threads = request.param == "threads"
    yield request.param
    ProxyThread.threads = False


def test_bytes_pass_unchanged_however_they_are_cut() -> None:
    peer = Peer()
    with ProxyThread([peer.port]) as proxy, socket.create_connection(("127.0.0.1", proxy.ports[0])) as c:
        sent = SET_MODE + STOP + SET_MODE
        for i in range(0, len(sent), 3):  # split
            c.sendall(sent[i : i + 3])
            time.sleep(0.002)
        c.sendall(STOP * 5 + GARBAGE)  # coalesced, then not a frame
        expected = sent + STOP * 5 + GARBAGE
        assert peer.wait_bytes(len(expected)) == expected
        back = bytes(range(256)) * 40 + STOP
        peer.accepted().sendall(back)
        assert read_exactly(c, len(back)) == back
        c.close()
        assert peer.eof.wait(5)
        peer.accepted().close()
        recs = proxy.wait_records(lambda rs: any(r.kind == CLOSE for r in rs))
    peer.close()
    requests = [r for r in recs if r.direction == "request"]
    assert [r.name for r in requests[:9]] == ["CMD_SET_MODE", "CMD_STOP", "CMD_SET_MODE"] + ["CMD_STOP"] * 5 + [
        "malformed"
    ]
    assert requests[8].kind == RAW and requests[8].error and requests[8].error.startswith("BadHeader")
    assert b"".join(r.raw for r in requests) == expected
    replies = [r for r in recs if r.direction == "reply"]
    assert replies[0].error and replies[0].error.startswith("BadHeader")  # bytes(range(256)) is no frame
    assert b"".join(r.raw for r in replies) == back
    assert next(r.kind for r in recs) == OPEN and recs[-1].detail == "by client (FIN)"


def test_half_close_travels_and_the_other_direction_keeps_going() -> None:
    peer = Peer()
    with ProxyThread([peer.port]) as proxy, socket.create_connection(("127.0.0.1", proxy.ports[0])) as c:
        c.sendall(STOP + STOP[:5])
        c.shutdown(socket.SHUT_WR)
        assert peer.eof.wait(5), "the client's FIN did not reach the target"
        assert bytes(peer.received) == STOP + STOP[:5]
        peer.accepted().sendall(b"late reply")
        peer.accepted().shutdown(socket.SHUT_WR)
        assert read_to_end(c) == b"late reply"
        recs = proxy.wait_records(lambda rs: any(r.kind == CLOSE for r in rs))
    peer.close()
    truncated = [r for r in recs if r.error and r.error.startswith("Truncated")]
    assert truncated[0].raw == STOP[:5] and truncated[0].direction == "request"


def test_a_reset_travels_as_a_reset() -> None:
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(5)
    with ProxyThread([server.getsockname()[1]]) as proxy, socket.create_connection(("127.0.0.1", proxy.ports[0])) as c:
        c.sendall(STOP)
        conn, _ = server.accept()
        assert read_exactly(conn, len(STOP)) == STOP
        conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        conn.close()  # RST
        c.settimeout(5)
        try:
            got = c.recv(100)
        except ConnectionResetError:
            got = None
        assert got is None, f"expected a reset, got {got!r}"
        recs = proxy.wait_records(lambda rs: any(r.kind == CLOSE for r in rs))
    server.close()
    assert recs[-1].detail.startswith("by target (reset")


def test_an_unreachable_target_closes_the_client() -> None:
    s = socket.create_server(("127.0.0.1", 0))
    dead = s.getsockname()[1]
    s.close()
    with ProxyThread([dead]) as proxy, socket.create_connection(("127.0.0.1", proxy.ports[0])) as c:
        assert read_to_end(c) == b""
        recs = proxy.wait_records(lambda rs: any(r.kind == CLOSE for r in rs))
    assert [r.kind for r in recs] == [OPEN, CLOSE]
    assert recs[1].detail.startswith("by proxy (target unreachable")


def test_a_slow_reader_slows_the_sender() -> None:
    peer = Peer()
    with ProxyThread([peer.port]) as proxy, socket.create_connection(("127.0.0.1", proxy.ports[0])) as c:
        c.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 16)
        conn = peer.accepted()
        conn.settimeout(2.0)
        blob = random.Random(1).randbytes(64 << 20)
        pushed = 0
        try:
            while pushed < len(blob):
                pushed += conn.send(blob[pushed : pushed + (1 << 20)])
        except TimeoutError:
            pass
        assert pushed < 32 << 20, f"{pushed} bytes went into a client that reads nothing: no back-pressure"
        conn.settimeout(None)
        got = bytearray()
        c.settimeout(10)

        def rest() -> None:
            conn.sendall(blob[pushed:])

        t = threading.Thread(target=rest)
        t.start()
        while len(got) < len(blob):
            got += c.recv(1 << 20)
        t.join()
        assert got == blob
        assert proxy.alive
    peer.close()


def test_garbage_and_abrupt_clients_do_not_stop_the_proxy() -> None:
    rng = random.Random(7)
    peer_sock = socket.create_server(("127.0.0.1", 0))
    peer_sock.settimeout(5)
    with ProxyThread([peer_sock.getsockname()[1]]) as proxy:
        for i in range(60):
            c = socket.create_connection(("127.0.0.1", proxy.ports[0]))
            conn, _ = peer_sock.accept()
            c.sendall(rng.randbytes(rng.randrange(1, 3000)) if i % 3 else b"\xff\x01\xfe\x02\xff\xff\xff\xff")
            conn.sendall(rng.randbytes(rng.randrange(1, 3000)))
            if i % 2:
                c.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            c.close()
            conn.close()
        with socket.create_connection(("127.0.0.1", proxy.ports[0])) as c:
            conn, _ = peer_sock.accept()
            c.sendall(STOP)
            assert read_exactly(conn, len(STOP)) == STOP
            conn.sendall(b"ok")
            assert read_exactly(c, 2) == b"ok"
            conn.close()
        recs = proxy.wait_records(lambda rs: sum(r.kind == CLOSE for r in rs) == 61)
        assert proxy.alive and proxy.error is None
    peer_sock.close()
    assert sum(r.kind == OPEN for r in recs) == 61
    assert any(r.error and r.error.startswith("FrameTooLarge") for r in recs)
    assert [r.name for r in recs if r.kind == FRAME and r.direction == "request"][-1] == "CMD_STOP"


def _refused(port: int, within: float) -> bool:
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
        except ConnectionRefusedError:
            return True
        time.sleep(0.05)
    return False


def test_while_the_target_does_not_listen_neither_does_the_proxy() -> None:
    """CMD_EXIT: 'the ports stop listening' - seen through the proxy too; and it listens again with the target."""
    s = socket.create_server(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    with ProxyThread([port]) as proxy:
        assert _refused(proxy.ports[0], 5.0), "the proxy still takes connections for a target that refuses them"
        back = socket.create_server(("127.0.0.1", port))
        back.settimeout(5)
        deadline = time.monotonic() + 5
        while True:
            try:
                c = socket.create_connection(("127.0.0.1", proxy.ports[0]), timeout=1)
                break
            except ConnectionRefusedError:
                assert time.monotonic() < deadline, "the proxy did not listen again"
                time.sleep(0.1)
        with c:
            conn, _ = back.accept()  # the proxy's probe first, then the client's own connection
            conn.close()
            conn, _ = back.accept()
            c.sendall(STOP)
            assert read_exactly(conn, len(STOP)) == STOP
            conn.close()
        back.close()


def test_a_stuck_recorder_does_not_hold_up_forwarding() -> None:
    """The observer gets the bytes after they moved: while it hangs, round trips go on; then it gets them all."""
    release = threading.Event()
    records: list[Record] = []

    def stuck(rec: Record) -> None:
        release.wait(30)
        records.append(rec)

    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(5)
    with ProxyThread([server.getsockname()[1]], Recorder([stuck])) as proxy:
        c = socket.create_connection(("127.0.0.1", proxy.ports[0]))
        conn, _ = server.accept()
        for k in range(50):
            c.sendall(STOP)
            assert read_exactly(conn, len(STOP)) == STOP, f"round trip {k} held up by the recorder"
            conn.sendall(STOP)
            assert read_exactly(c, len(STOP)) == STOP, f"round trip {k} held up by the recorder"
        assert not records
        release.set()
        deadline = time.monotonic() + 10
        while sum(r.kind == FRAME for r in records) < 100:
            assert time.monotonic() < deadline, f"{len(records)} records"
            time.sleep(0.01)
        c.close()
        conn.close()
    server.close()
    frames = [r for r in records if r.kind == FRAME]
    assert [r.direction for r in frames] == ["request", "reply"] * 50  # each request before the reply it caused


class _SlowToPassEnds(Recorder):
    """A recorder called from the forwarding threads (``threadsafe``, as the recorder process's pipe is) that is
    slow to take a client's FIN: the thread passing it on is held up, as by a full pipe."""

    threadsafe = True

    def __init__(self, hold: float) -> None:
        super().__init__([])
        self.hold = hold

    def half_closed(self, conn: int, now: float, c2s: bool) -> None:
        if c2s:
            time.sleep(self.hold)
        super().half_closed(conn, now, c2s)


def test_a_client_that_closes_and_reconnects_at_once_reaches_the_target_in_that_order() -> None:
    """The target (guide 6.1: one client per port) sees the first connection's FIN before the second's open, as
    it would without the proxy, though the thread passing the FIN on is held up: a target that turns a newcomer
    away while the port is taken would otherwise turn the client away (CI, stop 28: the replay test's recording
    had a client turned away by the reference server that its replay then found served)."""
    with contextlib.ExitStack() as stack:
        server = stack.enter_context(socket.create_server(("127.0.0.1", 0)))
        server.settimeout(5)
        proxy = stack.enter_context(ProxyThread([server.getsockname()[1]], _SlowToPassEnds(hold=0.4)))
        first = socket.create_connection(("127.0.0.1", proxy.ports[0]))
        served = stack.enter_context(server.accept()[0])
        first.sendall(STOP)
        assert read_exactly(served, len(STOP)) == STOP
        first.close()
        second = stack.enter_context(socket.create_connection(("127.0.0.1", proxy.ports[0])))
        newcomer = stack.enter_context(server.accept()[0])
        served.setblocking(False)
        try:
            left = served.recv(1) == b""
        except BlockingIOError:
            left = False
        assert left, "the second connection reached the target while the first was still there"
        second.sendall(STOP)
        assert read_exactly(newcomer, len(STOP)) == STOP


def _cpu_ticks(thread: threading.Thread) -> int:
    """CPU time (user + system, clock ticks) of one thread of this process, from /proc."""
    seconds = stat_cpu(Path(f"/proc/self/task/{thread.native_id}"))
    assert seconds is not None, f"{thread.name} is gone"
    return round(seconds * TICK)


def _forwarding_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name.startswith("proxy-")]


def test_an_idle_connection_costs_no_cpu_and_still_forwards() -> None:
    """Between the exchanges of a poller the forwarding blocks: an idle connection's threads take no CPU (whatever
    the proxy does after it moved bytes ends), and the bytes still pass both ways once the connection idled."""
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(5)
    with ProxyThread([server.getsockname()[1]]) as proxy, socket.create_connection(("127.0.0.1", proxy.ports[0])) as c:
        conn, _ = server.accept()
        for _ in range(20):  # a burst of exchanges, then silence
            c.sendall(STOP)
            assert read_exactly(conn, len(STOP)) == STOP
            conn.sendall(SET_MODE)
            assert read_exactly(c, len(SET_MODE)) == SET_MODE
        threads = _forwarding_threads()
        assert threads, "no forwarding thread"
        before = {t: _cpu_ticks(t) for t in threads}
        time.sleep(2.0)
        used = {t.name: _cpu_ticks(t) - before[t] for t in threads}
        assert all(ticks <= 20 for ticks in used.values()), f"CPU ticks over 2 s of silence: {used} (100/s: busy)"
        c.sendall(SET_MODE)
        assert read_exactly(conn, len(SET_MODE)) == SET_MODE
        conn.sendall(STOP)
        assert read_exactly(c, len(STOP)) == STOP
        conn.close()
        assert read_to_end(c) == b""
    server.close()


def _closing_target() -> tuple[socket.socket, threading.Thread]:
    """A target that reads each connection to its end and closes it, one connection after another."""
    server = socket.create_server(("127.0.0.1", 0))

    def serve() -> None:
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            with conn:
                read_to_end(conn)

    thread = threading.Thread(target=serve, daemon=True, name="closing-target")
    thread.start()
    return server, thread


def test_a_client_reconnecting_at_once_is_replayed_in_its_order(core: str) -> None:
    """A client (a process of its own) closes a connection and opens the next on the same port at once, sixty
    times. The proxy's stamps may not say so - a close is stamped by the thread that forwards it, the next open by
    the one that accepts it, and a thread waits for the interpreter up to milliseconds - but the replay's plan
    must: each connection waits for the one before it (replay.plan, one client per port), or a replay opens
    the next while the last is still there and the target turns it away."""
    server, _ = _closing_target()
    rounds = 60
    client = (
        "import socket\n"
        "for _ in range({n}):\n"
        "    with socket.create_connection(('127.0.0.1', {port})) as c:\n"
        "        c.sendall(bytes.fromhex('{stop}'))\n"
    )
    with ProxyThread([server.getsockname()[1]]) as proxy:
        code = client.format(n=rounds, port=proxy.ports[0], stop=STOP.hex())
        subprocess.run([sys.executable, "-c", code], check=True, timeout=30)
        recs = proxy.wait_records(lambda rs: sum(r.kind == CLOSE for r in rs) == rounds)
    server.close()
    scripts = {s.conn: s for s in plan(Session(0.0, (Route("l:1", "h:1"),), tuple(recs)))}
    assert len(scripts) == rounds
    unordered = [n for n in scripts if n > 1 and n - 1 not in scripts[n].after_closes]
    assert not unordered, (core, unordered)
