"""flight: sessions in flight side by side over real loopback sockets - paced deliveries, resets."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator

import pytest

from pltf.fuzz.case import Case, Delivery
from pltf.fuzz.flight import Flight, Single, fly, plain
from pltf.fuzz.target import Session
from pltf.fuzz.unit import Unit
from pltf.fuzz.verdict import judge
from pltf.fuzz.wire import CLOSE, frame
from pltf.spec.codec import HEADER, REPLIES, encode


class Listener:
    """A loopback server of one connection: reads until end-of-stream (or closes at once, unread), recording
    each read with its time."""

    def __init__(self, read: bool = True) -> None:
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.reads: list[tuple[float, bytes]] = []
        self.read = read
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.sock.accept()
        with conn:
            if not self.read:
                time.sleep(0.05)  # the client's bytes arrive, unread: the close resets the connection
                return
            while data := conn.recv(65536):
                self.reads.append((time.monotonic(), data))

    def close(self) -> None:
        self.thread.join(5.0)
        self.sock.close()


@pytest.fixture
def listeners() -> Iterator[list[Listener]]:
    made: list[Listener] = []
    yield made
    for listener in made:
        listener.close()


def test_a_slow_delivery_arrives_piece_by_piece_while_other_flights_go_on(listeners: list[Listener]) -> None:
    slow_target, quick_target = Listener(), Listener()
    listeners += [slow_target, quick_target]
    data = bytes(range(40))
    slow = Flight("127.0.0.1", slow_target.port, Session([data], Delivery("slow", 4, 0.0125), half_close=True), 2.0)
    quick = Flight("127.0.0.1", quick_target.port, Session([b"abc"], half_close=True), 2.0)
    t0 = time.monotonic()
    fly([slow, quick])
    slow_target.close()
    quick_target.close()
    assert b"".join(d for _, d in slow_target.reads) == data
    assert len(slow_target.reads) == 4  # one write per piece, each read on its own (the pauses part them)
    times = [t for t, _ in slow_target.reads]
    assert times[-1] - times[0] >= 3 * 0.0125 * 0.8
    assert quick_target.reads[-1][0] < times[-1]  # the quick flight did not wait for the slow one's pauses
    assert slow.done and quick.done and not slow.out.timed_out and time.monotonic() - t0 < 1.0


def test_a_bytewise_delivery_sends_every_byte_in_order(listeners: list[Listener]) -> None:
    target = Listener()
    listeners.append(target)
    data = b"\xff\x01\xfe\x02" + bytes(range(60))
    flight = Flight("127.0.0.1", target.port, Session([data], Delivery("bytewise"), half_close=True), 2.0)
    fly([flight])
    target.close()
    assert b"".join(d for _, d in target.reads) == data and flight.pos == len(data)
    assert flight.out.closed and not flight.reset


def test_a_close_with_our_bytes_unread_is_a_reset(listeners: list[Listener]) -> None:
    target = Listener(read=False)
    listeners.append(target)
    flight = Flight("127.0.0.1", target.port, Session([b"x" * 100], half_close=True), 2.0)
    fly([flight])
    assert flight.done and flight.reset and not flight.out.replies


def test_an_empty_session_is_sent_at_once() -> None:
    with socket.create_server(("127.0.0.1", 0)) as server:
        flight = Flight("127.0.0.1", server.getsockname()[1], Session([], Delivery("bytewise"), half_close=True), 0.3)
        conn, _ = server.accept()
        with conn:
            assert not flight.sending and conn.recv(10) == b""  # no bytes, our end-of-stream
        fly([flight])
        assert flight.done and flight.out.closed


class Answering:
    """A loopback server that answers every connection the same way: reads until our end-of-stream, writes
    ``reply`` and closes (``reply`` None: closes at once, unread)."""

    def __init__(self, reply: bytes | None) -> None:
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.reply = reply
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        for _ in range(2):
            conn, _ = self.sock.accept()
            with conn:
                if self.reply is None:
                    continue
                while conn.recv(65536):
                    pass
                conn.sendall(self.reply)

    def close(self) -> None:
        self.thread.join(5.0)
        self.sock.close()


LEAD_REPLY = encode(REPLIES.CMD_GET_POSITION(x=1, y=2, angle=3, vel_trans=0, vel_rot=0))
ANSWERS = {
    "the lead's reply": LEAD_REPLY,
    "nothing": b"",
    "a reply that does not decode": HEADER + b"\x00\x00\x00\x02\xfe\x00",
    "a reply cut off by the close": LEAD_REPLY[:-3],
    "the lead's reply twice": LEAD_REPLY * 2,
    "closed unread": None,
}


@pytest.mark.parametrize("answer", list(ANSWERS))
@pytest.mark.parametrize("lead", [True, False])
def test_a_plain_single_is_judged_as_a_flight_of_its_session_is(answer: str, lead: bool) -> None:
    """The plain single's one object and its counters give the verdict, replies and close the general flight
    gives for the same session, whatever the target answered."""
    unit = Unit([Case((frame(b"\xfe\x01"),), "gen.boundary", "id 254", expect=CLOSE, answered=())])
    assert plain(unit, lead, kept=False, fin_waits=False)
    server = Answering(ANSWERS[answer])
    try:
        single = Single("127.0.0.1", server.port, unit, lead, 2.0, False)
        fly([single])
        flight = Flight("127.0.0.1", server.port, unit.session(lead=lead), 2.0)
        fly([flight])
    finally:
        server.close()
    assert single.data == flight.data and single.expected == flight.expected
    assert single.verdict() == judge(flight.out, unit.owed(flight.session, len(flight.expected)), lead, False)
    assert [r.ID for r in single.replies] == [r.ID for r in flight.out.replies]
    assert (single.out.closed, single.out.refused, single.out.timed_out) == (True, False, False)
    assert single.session.frames == flight.session.frames
