"""flight: sessions in flight side by side over real loopback sockets - paced deliveries, resets."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator

import pytest

from pltf.fuzz.case import Delivery
from pltf.fuzz.flight import Flight, fly
from pltf.fuzz.target import Session


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
    # one write per piece, our FIN after the three pauses between them (the listener's reads are not counted: a
    # loaded machine that descheduled its thread for 100 ms read two pieces as one, hog run 37)
    assert [end for _, end in slow.sends] == [10, 20, 30, 40]
    assert slow.out.fin_ms is not None and slow.out.fin_ms >= 3 * 12.5 * 0.8
    times = [t for t, _ in slow_target.reads]
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
