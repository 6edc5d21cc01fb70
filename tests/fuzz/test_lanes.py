"""lanes: units on the ports, newcomers turned away, pipelining, a dear target's kept connection, a target gone.

No sockets: the target is a script that decides, per connection, what became of it; flights finish when the
(patched) select loop steps them, oldest first, as a target serving one client per port would finish them."""

from __future__ import annotations

import collections
import itertools
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

import pltf.fuzz.lanes as lanes_module
from pltf.fuzz import inflight
from pltf.fuzz.case import Case
from pltf.fuzz.lanes import DONE, STOPPED, InFlight, Lanes
from pltf.fuzz.pace import Pace
from pltf.fuzz.target import Outcome, Session, session_reply_ids
from pltf.fuzz.unit import Unit
from pltf.fuzz.verdict import OK, Verdict
from pltf.fuzz.wire import frame, survey
from pltf.spec.codec import REQUESTS, encode

SERVE, TURN_AWAY, REFUSE, SILENCE = "serve", "turn-away", "refuse", "silence"


class FakeSock:
    def shutdown(self, how: int) -> None:
        pass

    def settimeout(self, t: float) -> None:
        pass

    def recv(self, n: int) -> bytes:
        return b""

    def close(self) -> None:
        pass


class FakeFlight:
    """What ``Lanes`` reads of a flight; the script fills in its outcome when it finishes."""

    def __init__(self, target: Target, port: int, session: Session, deadline: float, sock: Any) -> None:
        self.target, self.port, self.session, self.sock = target, port, session, sock
        self.expected = session_reply_ids(session) + ([REQUESTS.CMD_GET_STATUS.ID] if session.sync else [])
        self.out = Outcome()
        self.started = time.monotonic()
        self.budget, self.deadline = deadline, self.started + deadline
        self.done, self.connected, self.sending, self.kept = False, True, False, None
        self.data = session.data
        self.half_close = session.half_close
        self.behind = any(not f.done for f in target.flights if f.port == port)  # another of ours holds the port
        self.order = len(target.flights)

    def finish(self) -> None:
        what = self.target.rule(self)
        out = self.out
        if what == SERVE:
            out.replies = [object() for _ in self.expected]  # type: ignore[misc]
            out.got = 100
            if self.session.half_close:
                out.closed = True
            else:
                self.kept = self.sock or FakeSock()
        elif what == TURN_AWAY:
            out.closed = True
        elif what == REFUSE:
            out.refused = True
        else:
            out.timed_out = True
        self.done = True


class Target:
    def __init__(self, rule: Callable[[FakeFlight], str]) -> None:
        self.rule = rule
        self.flights: list[FakeFlight] = []

    def connect(self, host: str, port: int, session: Session, deadline: float, sock: Any = None) -> FakeFlight:
        f = FakeFlight(self, port, session, deadline, sock)
        self.flights.append(f)
        if not session.half_close and sock is not None:
            f.behind = False  # on the kept connection
        return f


@pytest.fixture(autouse=True)
def oldest_first(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """The select loop, played: the oldest flight not done finishes (``fly`` runs them all out)."""

    def step(flights: list[FakeFlight], until: float | None = None, poller: Any = None) -> list[FakeFlight]:
        live = [f for f in flights if not f.done]
        if live:
            min(live, key=lambda f: f.order).finish()
        return [f for f in flights if f.done]

    def fly(flights: list[FakeFlight]) -> None:
        for f in flights:
            if not f.done:
                f.finish()

    monkeypatch.setattr(lanes_module, "step_flights", step)
    monkeypatch.setattr(lanes_module, "fly", fly)
    yield


def case(data: bytes) -> Case:
    kind, answered = survey(data)
    return Case((data,), "gen.boundary", "x", expect=kind, answered=tuple(answered))


ACCEPTED = case(encode(REQUESTS.CMD_GET_POSITION()))
REFUSED = case(frame(b"\xfe"))  # an unknown id: the target closes the connection


def lanes_for(target: Target, **kw: Any) -> Lanes:
    return Lanes("127.0.0.1", (1, 2), 1.0, connect=target.connect, patience=kw.pop("patience", 0.05), **kw)


def judged(into: list[InFlight], verdict: str | None = None) -> Callable[[InFlight, Verdict], bool]:
    def judge(e: InFlight, v: Verdict) -> bool:
        into.append(e)
        return verdict is None or v.kind != verdict

    return judge


def test_a_unit_turned_away_runs_again_and_is_judged_once() -> None:
    def every_second_try(f: FakeFlight) -> str:  # port 2 is freed only some time after its client left
        n = sum(1 for g in target.flights if g.port == 2 and g.done)
        return SERVE if f.port == 1 or n % 2 else TURN_AWAY

    target = Target(every_second_try)
    lanes = lanes_for(target, pipelining=False)
    units = [Unit([REFUSED]) for _ in range(20)]
    lanes.add(units)
    out: list[InFlight] = []
    assert lanes.run(judged(out)) == DONE
    assert sorted(id(e.unit) for e in out) == sorted(id(u) for u in units)  # each judged once, all served
    assert all(e.verdict is not None and e.verdict.kind == OK for e in out)
    assert sum(g.turn_aways for g in lanes.gates) > 0 and len(target.flights) > len(units)
    retried = [u for u in units if u.tries]
    assert retried and all(u.session().gate for u in retried)  # a unit that runs again waits for the lead's reply


def test_pipelined_newcomers_turned_away_stop_pipelining_without_a_verdict() -> None:
    target = Target(lambda f: TURN_AWAY if f.behind else SERVE)  # one client at a time, newcomers closed
    lanes = lanes_for(target)
    units = [Unit([REFUSED]) for _ in range(60)]
    lanes.add(units)
    out: list[InFlight] = []
    assert lanes.run(judged(out)) == DONE
    assert len(out) == 60 and all(e.verdict is not None and e.verdict.kind == OK for e in out)
    assert not any(g.pipelining for g in lanes.gates) and lanes.turned_away
    assert all(g.pipelined for g in lanes.gates)


def test_a_backlog_serves_pipelined_newcomers_in_turn() -> None:
    target = Target(lambda f: SERVE)  # accept-once: a newcomer waits and is served when its turn comes
    lanes = lanes_for(target)
    lanes.add([Unit([REFUSED]) for _ in range(40)])
    assert lanes.run(judged([])) == DONE
    assert all(g.pipelining and g.pipelined for g in lanes.gates) and not any(g.turn_aways for g in lanes.gates)


@pytest.mark.parametrize(("what", "gone"), [(REFUSE, "dead"), (SILENCE, "hang"), (TURN_AWAY, "deaf")])
def test_a_target_no_port_serves_is_gone_and_nothing_is_judged(what: str, gone: str) -> None:
    target = Target(lambda f: what)
    lanes = lanes_for(target)
    lanes.add([Unit([ACCEPTED]) for _ in range(5)])
    out: list[InFlight] = []
    t0 = time.monotonic()
    assert lanes.run(judged(out)) == gone
    assert not out and time.monotonic() - t0 < 2.0
    assert [e.unit for e in lanes.recent]  # the units sent last, for the finding


def test_a_port_that_serves_nobody_while_the_other_does_is_stuck() -> None:
    target = Target(lambda f: TURN_AWAY if f.port == 2 else SERVE)
    lanes = lanes_for(target, pipelining=False, patience=0.002)
    lanes.add([Unit([REFUSED]) for _ in range(5000)])
    assert lanes.run(judged([])) == "stall" and lanes.stuck == 1


def test_a_stuck_port_names_the_unit_it_left_unanswered() -> None:
    """Issue 17: the unit that stalled a port is known after other units pushed it out of ``recent``."""
    stall = case(frame(b"\x4d"))  # id 77: the fragile server's stall
    held: set[int] = set()

    def rule(f: FakeFlight) -> str:
        if f.port in held:
            return TURN_AWAY  # the stalled connection holds the port
        if stall.frames[0] in f.session.frames:
            held.add(f.port)
            return SILENCE
        return SERVE

    lanes = lanes_for(Target(rule), pipelining=False, patience=0.05)
    culprit = Unit([stall])
    lanes.add([*(Unit([REFUSED]) for _ in range(3)), culprit, *(Unit([REFUSED]) for _ in range(5000))])
    assert lanes.run(judged([])) == "stall"
    assert culprit not in [e.unit for e in lanes.recent]  # the other port ran more than RECENT units meanwhile
    assert lanes.left_unanswered(lanes.stuck) is culprit


def test_a_port_left_silent_while_the_other_idles_is_asked_about_once_the_flights_ran_out() -> None:
    target = Target(lambda f: SILENCE if f.port == 2 else SERVE)
    lanes = lanes_for(target, pipelining=False)
    lanes.add([Unit([REFUSED]), Unit([REFUSED])])  # one per port: port 1 idles after its unit
    assert lanes.run(judged([])) == "stall" and lanes.stuck == 1
    assert target.flights[-1].port == 1 and not target.flights[-1].session.frames[1:]  # a status-only check


def test_a_dear_target_keeps_a_connection_for_accepted_cases() -> None:
    target = Target(lambda f: SERVE)
    lanes = lanes_for(target)
    lanes.dear = True
    lanes.add([Unit([ACCEPTED]) if k % 2 else Unit([REFUSED]) for k in range(10)])
    out: list[InFlight] = []
    assert lanes.run(judged(out)) == DONE
    kept = [e for e in out if e.port == 0]
    assert kept and all(e.unit.keep and e.kept for e in kept)  # port 0: accepted cases, one connection
    assert [e.led for e in kept] == [True] + [False] * (len(kept) - 1)  # served once: no lead after the first
    assert all(e.port == 1 for e in out if not e.unit.keep)  # fresh connections for the cases refused
    assert lanes.kept is not None
    lanes.release()
    assert lanes.kept is None


def test_a_suspicion_stops_new_units_and_the_ones_in_flight_are_judged() -> None:
    target = Target(lambda f: SERVE if len(target.flights) != 3 else TURN_AWAY)
    lanes = lanes_for(target)
    lanes.add([Unit([ACCEPTED]) for _ in range(30)])
    out: list[InFlight] = []
    calls = {"n": 0}

    def judge(e: InFlight, v: Verdict) -> bool:
        out.append(e)
        calls["n"] += 1
        return calls["n"] != 5

    assert lanes.run(judge) == STOPPED
    assert 5 <= len(out) < 30 and len(lanes.todo) == 30 - len(out)
    assert lanes.run(judged(out)) == DONE and len(out) == 30  # the rest runs when asked again


def test_units_started_on_the_other_port_extend_a_unit_in_flight_by_shared_units_allowances_at_most() -> None:
    """The kept connection's batches, one after the other, must not push a stalled single's deadline on for as
    long as they come: the single gets the allowances of ``SHARED_UNITS`` of them, then its own deadline holds."""
    from types import SimpleNamespace

    lanes = lanes_for(Target(lambda f: SERVE))
    now = time.monotonic()
    single = SimpleNamespace(done=False, budget=1.0, deadline=now + 1.0)
    lanes.flights[1].append(InFlight(single, Unit([REFUSED]), 1, False, False, True, now))  # type: ignore[arg-type]
    for _ in range(50):  # batches on port 0, each with an allowance of 0.5 s for its size
        batch = SimpleNamespace(done=False, budget=1.5, deadline=time.monotonic() + 1.5)
        lanes._share_allowances(0, batch)  # type: ignore[arg-type]
        batch.done = True
    assert single.deadline == pytest.approx(now + 1.0 + inflight.SHARED_UNITS * 0.5)


def test_a_paced_kept_connection_starts_a_batch_only_after_the_singles_the_last_one_owes() -> None:
    """The trial's dear way (``pltf.fuzz.pace``): a batch of 8 cases at half a single per case owes 4 singles on
    the other port; the next batch waits for them (those served while it ran count)."""
    target = Target(lambda f: SERVE)
    out: list[InFlight] = []
    singles_at_batch: list[int] = []

    def connect(host: str, port: int, session: Session, deadline: float, sock: Any = None) -> FakeFlight:
        if port == 1 and not session.half_close:  # a batch on the kept connection of port 0 starts
            singles_at_batch.append(sum(1 for e in out if not e.unit.keep))
        return target.connect(host, port, session, deadline, sock)

    lanes = Lanes("127.0.0.1", (1, 2), 1.0, connect=connect, patience=0.05)
    lanes.dear, lanes.pace = True, Pace(turn=0.5)
    lanes.add([Unit([ACCEPTED] * 8) for _ in range(3)] + [Unit([REFUSED]) for _ in range(20)])
    assert lanes.run(judged(out)) == DONE
    assert len(out) == 23 and len(singles_at_batch) == 3
    assert all(b - a >= 4 for a, b in itertools.pairwise(singles_at_batch))
    assert all(e.port == 1 for e in out if not e.unit.keep)


def test_a_paced_window_of_batches_ends_when_the_singles_owed_were_served() -> None:
    target = Target(lambda f: SERVE)
    lanes = lanes_for(target)
    lanes.dear, lanes.pace = True, Pace(turn=0.5)
    lanes.add([Unit([ACCEPTED] * 8), *(Unit([REFUSED]) for _ in range(12))])
    out: list[InFlight] = []
    assert lanes.run(judged(out), batches_only=True) == DONE
    assert sum(1 for e in out if not e.unit.keep) >= 4 and lanes.todo  # the other singles go on in the next call
    lanes.add([Unit([ACCEPTED] * 8)])  # no single waits for the kept connection's next batch: it does not wait
    lanes.todo = collections.deque(u for u in lanes.todo if u.keep)
    assert lanes.run(judged(out), batches_only=True) == DONE
