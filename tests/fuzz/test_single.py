"""The plain single (``pltf.fuzz.single``), in Python and in C: judged as a ``Flight`` of its session is, on the
lanes' epoll (``pltf.fuzz.poller``) beside Python flights."""

from __future__ import annotations

import socket
import threading
import time

import pytest

from pltf.fuzz.case import Case
from pltf.fuzz.flight import Flight, fly, step_flights
from pltf.fuzz.poller import Poller
from pltf.fuzz.single import NATIVE, CSingle, Single, plain, single
from pltf.fuzz.unit import Unit
from pltf.fuzz.verdict import judge
from pltf.fuzz.wire import CLOSE, frame
from pltf.spec.codec import HEADER, REPLIES, encode


class Answering:
    """A loopback server that answers every connection the same way: reads until our end-of-stream, writes
    ``reply`` and closes (``reply`` None: closes at once, unread)."""

    def __init__(self, reply: bytes | None, connections: int = 2) -> None:
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.reply, self.connections = reply, connections
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        for _ in range(self.connections):
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


IMPLS = ["python", "c"] if NATIVE else ["python"]


def make_single(impl: str, port: int, unit: Unit, lead: bool) -> Single | CSingle:
    """A plain single of either kind: the Python oracle, or the C one driven by ``select`` (no pool)."""
    if impl == "python":
        return Single("127.0.0.1", port, unit, lead, 2.0, False)
    made = single(None, "127.0.0.1", port, unit, lead, 2.0, False)
    assert type(made) is CSingle
    return made


REFUSED_UNIT = Unit([Case((frame(b"\xfe\x01"),), "gen.boundary", "id 254", expect=CLOSE, answered=())])


@pytest.mark.parametrize("impl", IMPLS)
@pytest.mark.parametrize("answer", list(ANSWERS))
@pytest.mark.parametrize("lead", [True, False])
def test_a_plain_single_is_judged_as_a_flight_of_its_session_is(impl: str, answer: str, lead: bool) -> None:
    """The plain single's one object and its counters (in Python, or in C) give the verdict, replies and close the
    general flight gives for the same session, whatever the target answered."""
    unit = REFUSED_UNIT
    assert plain(unit, lead, kept=False, fin_waits=False)
    server = Answering(ANSWERS[answer])
    try:
        one = make_single(impl, server.port, unit, lead)
        fly([one])
        flight = Flight("127.0.0.1", server.port, unit.session(lead=lead), 2.0)
        fly([flight])
    finally:
        server.close()
    assert one.data == flight.data and one.expected == flight.expected
    assert one.verdict() == judge(flight.out, unit.owed(flight.session, len(flight.expected)), lead, False)
    assert [r.ID for r in one.replies] == [r.ID for r in flight.out.replies]
    assert one.bad_reply == flight.out.bad_reply
    assert (one.out.closed, one.out.refused, one.out.timed_out) == (True, False, False)
    assert one.session.frames == flight.session.frames
    assert one.pos == len(one.data) and [end for _, end in one.sends] == [len(one.data)]


@pytest.mark.parametrize("impl", IMPLS)
def test_a_plain_single_to_a_port_nobody_listens_on_is_refused(impl: str) -> None:
    with socket.socket() as s:  # a port that was free a moment ago
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    one = make_single(impl, port, REFUSED_UNIT, True)
    fly([one])
    assert one.done and one.out.refused and not one.replies
    assert one.verdict() == judge(one.out, 1, True, False)  # turned away: refused


@pytest.mark.skipif(not NATIVE, reason="the C extension _singles is not built")
def test_c_singles_run_on_the_lanes_epoll_beside_python_flights_and_time_out_there() -> None:
    """Many C singles at once on one ``Poller``: each reaches the reply, a Python flight on the same epoll too, and
    one whose target never answers ends at its deadline."""
    server = Answering(LEAD_REPLY, connections=3)
    silent = socket.create_server(("127.0.0.1", 0))  # accepts (the backlog) and never answers
    poller = Poller()
    try:
        many = [single(poller.ep, "127.0.0.1", server.port, REFUSED_UNIT, True, 2.0, False) for _ in range(2)]
        stuck = single(poller.ep, "127.0.0.1", silent.getsockname()[1], REFUSED_UNIT, True, 0.1, False)
        python = Flight("127.0.0.1", server.port, REFUSED_UNIT.session(lead=True), 2.0)
        flights: list[Flight | CSingle] = [*many, stuck, python]
        t0 = time.monotonic()
        while not all(f.done for f in flights):
            step_flights([f for f in flights if not f.done], poller=poller)
        assert time.monotonic() - t0 < 2.0
    finally:
        server.close()
        silent.close()
        poller.close()
    assert [f.verdict().kind for f in many] == ["ok", "ok"] and all(len(f.replies) == 1 for f in many)
    assert [r.ID for r in python.out.replies] == [LEAD_REPLY[8]] and python.out.closed
    assert stuck.timed_out and stuck.verdict().how == "timed-out" and stuck.fileno() == -1


@pytest.mark.skipif(not NATIVE, reason="the C extension _singles is not built")
def test_c_single_frames_walks_the_reply_stream_by_the_wire_format() -> None:
    """``frames``: the ids of the whole frames (guide 6.2) and whether nothing else came."""
    for reply, want in [
        (LEAD_REPLY * 2, (bytes([LEAD_REPLY[8]] * 2), True)),
        (LEAD_REPLY[:-3], (b"", False)),
        (b"", (b"", True)),
    ]:
        server = Answering(reply, connections=1)
        try:
            one = make_single("c", server.port, REFUSED_UNIT, True)
            fly([one])
        finally:
            server.close()
        assert isinstance(one, CSingle) and one.frames() == want


def run_all(poller: Poller, run: object, flights: int) -> tuple[list[CSingle], list[CSingle]]:
    """Drive a ``_singles.Run`` on its pool until each of its singles finished or came back unstarted."""
    done: list[CSingle] = []
    back: list[CSingle] = []
    t0 = time.monotonic()
    while len(done) + len(back) < flights and time.monotonic() - t0 < 10.0:
        poller.step([], until=time.monotonic() + 0.2)
        done += run.take()  # type: ignore[attr-defined]
        if run.halted and not run.flying:  # type: ignore[attr-defined]
            back += run.unstarted()  # type: ignore[attr-defined]
    return done, back


@pytest.mark.skipif(not NATIVE, reason="the C extension _singles is not built")
@pytest.mark.parametrize("answer", list(ANSWERS))
@pytest.mark.parametrize("lead", [True, False])
def test_plain_singles_in_bulk_are_judged_as_a_flight_of_each_session_is(answer: str, lead: bool) -> None:
    """Three plain singles handed to one port's run at once (``_singles.Run``, as the lanes hand them): each
    started in its turn (pipelined behind the one before), judged as the general flight of its session, in port
    order; a single not admitted stops the run and the ones it did not start come back."""
    from pltf.fuzz._singles import Run

    unit = REFUSED_UNIT
    server = Answering(ANSWERS[answer], connections=4)
    poller = Poller()
    try:
        run = Run(poller.ep, 4)
        mine = [single(poller.ep, "127.0.0.1", server.port, unit, lead, 2.0, False, start=False) for _ in range(3)]
        for s in mine:
            run.add(s, lead, True, s.budget - 2.0)
        run.advance()
        done, back = run_all(poller, run, len(mine))
        flight = Flight("127.0.0.1", server.port, unit.session(lead=lead), 2.0)
        fly([flight])
    finally:
        server.close()
        poller.close()
    want = judge(flight.out, unit.owed(flight.session, len(flight.expected)), lead, False)
    assert done[0] is mine[0] and done[0].verdict() == want
    assert [r.ID for r in done[0].replies] == [r.ID for r in flight.out.replies]
    if want.kind == "not-admitted":  # the rest stop behind it: back unstarted, or run out and judged the same
        assert run.halted and back == mine[len(done) :] and all(not s.sends for s in back)
        return
    assert done == mine and not back and [s.verdict() for s in done] == [want] * 3
    assert [s.behind for s in done] == [False, True, True]  # pipelined behind the first (the server is sequential)
    assert all(s.pos == len(s.data) for s in done)
