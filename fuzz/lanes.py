"""Units in flight on the target's ports: one lane per port, pipelining, and newcomers turned away run again.

Rules:
- Both ports take every command, one client each (guide 6.1), so units run in two lanes driven by one
  ``select`` loop (``pltf.fuzz.flight``). Each unit gets its own connection and opens with the lead
  (``pltf.fuzz.unit``) - once ``WARMUP`` units were served and none turned away, a unit that owes no reply goes
  without, but for one in ``LEAD_EVERY`` (``_led``); the first unit not served brings the lead back for good.
- A unit the target did not admit (``pltf.fuzz.verdict``) goes back to the front of the queue and runs again
  alone on a port whose backoff has passed (``pltf.fuzz.gate``); it is never judged or counted before it was
  served. When no port has admitted us for ``patience`` seconds the target is gone (dead or hung), when one
  port has not while the other has it is stuck (a stall): the lanes stop and say so.
- Pipelining: behind a small unit fully sent, its write side shut and owing nothing but statuses, up to three
  more small units wait connected on its port while the port's gate allows it; a waiting unit's deadline runs
  from its turn.
- A *dear* port (a connection costs milliseconds of release: a proxy, a slow accept) keeps one connection on
  the first port (``kept``) for the units of accepted cases (batches, big documents): one after the other, each
  ended by its sync reply, while the other port spends fresh connections on the cases the target should refuse
  (and on the others when none waits). On the trial's dear way (``pace``) a batch starts only once the singles
  the batch before it owes were served, or none waits (``pltf.fuzz.pace``).
- Deadlines: a unit's budget (``pltf.fuzz.target.session_deadline``) runs from its turn on its port, plus the
  size allowances of the units in flight on the other ports (a target may serve one port at a time). Of the
  units that start on other ports while it is in flight it gets at most ``SHARED_UNITS`` allowances
  (``pltf.fuzz.inflight.grant``): a target that serves its ports in turn comes back to it after one of them.
  Unbounded, the kept connection's batches, one after the other, would push a stalled single's deadline on for
  as long as they come, and the stall would never show.
- Every flight, in the lanes or alone (replays, checks), goes into ``log`` (the last ``LOG``) as it starts:
  ``sent()`` is what the target was sent lately, in the order it was written (``pltf.fuzz.sent``), units still
  in flight and units not admitted too (a target that reads every connection may have seen them).
- Every admitted unit is handed to the campaign's ``judge`` in its port's order; a False answer stops new units,
  the ones in flight run out (and are judged too) and ``run`` returns: the ports are then free for replays.
- Plain singles in bulk (``bulk``, where ``_singles`` is built): a port with nothing of Python's on it hands the
  plain singles it would take next to C, which starts them as these rules do; Python takes them back a few at a
  time and counts them in one loop (``pltf.fuzz.runs``). While a run holds a port, Python starts nothing else
  there.
"""

from __future__ import annotations

import collections
import contextlib
import socket
import time
from collections.abc import Callable

from pltf.fuzz.flight import NATIVE, Flight, fly, step_flights
from pltf.fuzz.gate import DEPTH, Gate
from pltf.fuzz.inflight import InFlight, Judge, JudgeClean, grant
from pltf.fuzz.pace import Pace
from pltf.fuzz.poller import Poller
from pltf.fuzz.runs import Bulk, plain_unit
from pltf.fuzz.sent import segments
from pltf.fuzz.single import CSingle, Flying, Single, plain, single
from pltf.fuzz.target import LEAD_IDS, Session, session_deadline
from pltf.fuzz.unit import PIPELINE_BYTES, Unit
from pltf.fuzz.verdict import NOT_ADMITTED, Liveness, Verdict, judge

try:
    from pltf.fuzz._singles import Run
except ImportError:  # built without a compiler, or PLTF_NO_EXTENSIONS=1
    Run = None  # type: ignore[assignment,misc]

RECENT = 16  # units remembered as "sent last"
LOG = 1024  # flights remembered for ``sent`` (about eight windows of cases)
WARMUP = 256  # units served, none turned away, before some may go without a lead
LEAD_EVERY = 4  # then: one unit in so many on a port keeps it (the liveness probe), and every unit that owes replies
DONE, STOPPED = "done", "stopped"


FlightFactory = Callable[..., Flight]


class Lanes:
    bulk = NATIVE  # plain singles in bulk, in C (``_singles.Run``); False: each through ``_start`` and ``_done``

    def __init__(
        self,
        host: str,
        ports: tuple[int, ...],
        deadline: float,
        pipelining: bool = True,
        patience: float | None = None,
        connect: FlightFactory = Flight,
        active: int | None = None,
        lead_every: int = LEAD_EVERY,
    ) -> None:
        """``active``: how many of the ports carry units (the first ones; the others only replays and checks)."""
        self.host, self.ports, self.deadline = host, ports, deadline
        self.connect = connect
        self.active = len(ports) if active is None else min(active, len(ports))
        self.gates = [Gate(k, pipelining) for k in range(len(ports))]
        self.patience = patience if patience is not None else max(1.0, 2 * deadline)
        self.live = Liveness(self.active, self.patience, time.monotonic())
        self.turned_away: list[str] = []  # the unit that stopped pipelining on a port
        self.served = 0  # units admitted
        self.unled = False  # units that owe nothing may go without the lead (``WARMUP``)
        self.unled_ever_off = False  # a newcomer was turned away: every unit keeps its lead for good
        self.since_lead = [0] * len(ports)
        self.lead_every = max(1, lead_every)
        self.flights: list[collections.deque[InFlight]] = [collections.deque() for _ in ports]
        self.todo: collections.deque[Unit] = collections.deque()
        self.recent: collections.deque[InFlight] = collections.deque(maxlen=RECENT)
        self.log: collections.deque[Flying] = collections.deque(maxlen=LOG)  # every flight, as it started
        self.kept: socket.socket | None = None
        self.dear = False  # set by the campaign from the gates' release
        self.pace: Pace | None = None  # the dear way's batches take turns with the singles (``pltf.fuzz.pace``)
        self.stop = False
        self.gone: str | None = None  # "dead", "hang" or "stall" once the lanes saw it
        self.stuck: int | None = None  # the port of a stall
        self.suspect: int | None = None  # a port that has not served us for ``patience``: are the others alive?
        self.adapt: Callable[[Session], Session] = _as_is  # a session as the target needs it (``pltf.fuzz.profile``)
        # what ``adapt`` does, for the plain singles that skip it (``pltf.fuzz.single.Single``): our FIN waits for the
        # replies asked for; frames_as_is False (it rewrites frames: CONNECT_TO_PLTF first): no plain singles
        self.fin_waits = False
        self.frames_as_is = True
        self.poller = Poller()
        self.runs: list[Run | None] = [None] * len(ports)  # each port's plain singles in C (``pltf.fuzz.runs``)
        self.in_bulk = Bulk(self)

    # ------------------------------------------------------------------ queue
    def add(self, units: list[Unit]) -> None:
        self.todo.extend(units)

    def fresh_waiting(self) -> int:
        """Units queued that need a fresh connection (a case the target should refuse closes it)."""
        return sum(1 for u in self.todo if not u.keep) + sum(r.waiting for r in self.runs if r is not None)

    def clear_queue(self) -> None:
        """Nothing queued runs any more (the units in flight run out): the queue and the singles waiting in C."""
        self.in_bulk.halt()
        self.todo.clear()

    # ------------------------------------------------------------------ the loop
    def run(self, judge_unit: Judge, batches_only: bool = False, judge_clean: JudgeClean | None = None) -> str:
        """Run the queue; DONE when it is empty (``batches_only``: when no unit of accepted cases is queued or in
        flight - the others go on in the next call), STOPPED when ``judge_unit`` said stop, else "dead", "hang",
        "deaf" or "stall" (``gone``). ``judge_clean``: the plain singles that ran in C and were clean, at once."""
        self.stop = False
        while True:
            if not self.stop and self.gone is None:
                self._fill()
            else:
                self.in_bulk.halt()
            live = [e.flight for q in self.flights for e in q if not e.flight.done]
            if batches_only and not self.stop and self.gone is None and not self._batches_pending():
                return DONE
            runs = [(k, r) for k, r in enumerate(self.runs) if r is not None and r.active]
            if runs:
                self._step_runs(runs, live, judge_unit, judge_clean)
            elif not live and not any(self.flights):
                ended = self._idle()
                if ended is not None:
                    return ended
                continue
            elif not any(q and q[0].flight.done for q in self.flights):
                step_flights(live, until=self._next_retry(), poller=self.poller)
            for q in self.flights:
                while q and q[0].flight.done:
                    e = q.popleft()
                    _restart_clocks(q)
                    self._done(e, judge_unit)

    def _idle(self) -> str | None:
        """Nothing in flight: how ``run`` ends (None: it goes on, after the nearest backoff)."""
        if self.suspect is not None:
            self._check_suspect()
        if self.gone is not None:
            gone, self.gone = self.gone, None
            return gone
        if self.stop:
            return STOPPED
        if not self.todo:
            return DONE
        wait = min(g.retry_at for g in self.gates[: self.active]) - time.monotonic()
        time.sleep(max(0.0, min(wait, 0.05)))
        return None

    def _step_runs(
        self, runs: list[tuple[int, Run]], live: list[Flying], judge_unit: Judge, judge_clean: JudgeClean | None
    ) -> None:
        """With runs in C: one wait on the epoll, unless something is ready already (C goes on by itself until a
        run has singles for Python or wants more), then what the runs finished."""
        if not any(r.ready for _, r in runs) and not any(q and q[0].flight.done for q in self.flights):
            self.in_bulk.share(runs)
            self.poller.step(live, until=self._next_retry())
        for k, r in runs:
            self.in_bulk.take(k, r, judge_unit, judge_clean)

    def _batches_pending(self) -> bool:
        """Units of accepted cases queued or in flight (on a dear target: the kept connection's), or singles the
        last of them still owes the other ports (``pltf.fuzz.pace``)."""
        if self.dear and self.pace is not None and not self.pace.ready(self._singles_waiting()):
            return True
        return any(u.keep for u in self.todo) or any(e.unit.keep for q in self.flights for e in q)

    def _next_retry(self) -> float | None:
        now = time.monotonic()
        waits = [g.retry_at for g in self.gates if g.retry_at > now]
        return min(waits) if self.todo and waits else None

    def _fill(self) -> None:
        """Start units on every port that takes one now."""
        now = time.monotonic()
        todo = self.todo
        bulk = self._bulk()
        for k in range(self.active):
            gate, q = self.gates[k], self.flights[k]
            run = self.runs[k]
            if run is not None and run.active:  # the port's plain singles run in C: more of them, or nothing
                if todo and not run.halted and now >= gate.retry_at:
                    self.in_bulk.feed(k, run)
                else:
                    run.hungry = False  # nothing to give it now: it should not ask
                continue
            while todo and now >= gate.retry_at:  # ``Gate.may_connect``
                unit = self._pick(k)
                if unit is None or not self._may_start(k, unit):
                    break
                if bulk and not q and plain_unit(unit):
                    run = self.runs[k] = Run(self.poller.ep, DEPTH if gate.pipelining else 1)
                    self.in_bulk.feed(k, run)
                    break
                if unit is todo[0]:
                    todo.popleft()
                else:
                    todo.remove(unit)
                q.append(self._start(k, unit))

    def _pick(self, k: int) -> Unit | None:
        """The unit port ``k`` takes next: the queue's first, except on a dear target (batches on the kept
        connection of port 0, singles first on the others)."""
        if not self.dear or self.active < 2:
            head = self.todo[0]  # the common case: the queue's first is not pinned elsewhere
            if head.pin is None or head.pin == k:
                return head
            return next((u for u in self.todo if u.pin is None or u.pin == k), None)
        mine = (u for u in self.todo if u.pin is None or u.pin == k)
        first = None
        for u in mine:
            if u.keep == (k == 0):
                return u
            first = first or u
        return None if k == 0 else first

    def _may_start(self, k: int, unit: Unit) -> bool:
        q = self.flights[k]
        if self.dear and k == 0:  # the kept connection carries one batch at a time; paced, in its turn
            run = self.runs[0]
            idle = not q and (run is None or not run.active)
            return idle and (self.pace is None or self.pace.ready(self._singles_waiting()))
        if not q:
            return True
        gate = self.gates[k]
        if not gate.pipelining or unit.tries or len(q) >= DEPTH or not unit.whole:
            return False
        f = q[-1].flight
        return (
            f.connected
            and not f.sending
            and f.half_close
            and len(f.data) <= PIPELINE_BYTES
            and all(i in LEAD_IDS for i in f.expected)
        )

    def _singles_waiting(self) -> bool:
        """Singles queued for the other ports (not pinned to port 0) or in flight there."""
        return (
            any(not u.keep and u.pin != 0 for u in self.todo)
            or any(not e.unit.keep for q in self.flights[1:] for e in q)
            or any(r is not None and r.active for r in self.runs[1:])
        )

    def _led(self, k: int, unit: Unit, fresh: bool) -> bool:
        """Whether a unit on a fresh connection opens with the lead: always, until ``WARMUP`` units were served
        with none turned away; then a unit that owes no reply (a case the target should refuse, written whole)
        goes without, except one in ``LEAD_EVERY`` on the port, which probes. A reply costs a target a write
        (on the reference server a third of a refused case's cost)."""
        if not fresh:
            return False
        self.since_lead[k] += 1
        if not self.unled or unit.keep or unit.tries or not unit.whole or self.since_lead[k] >= self.lead_every:
            self.since_lead[k] = 0
            return True
        return False

    def _start(self, k: int, unit: Unit) -> InFlight:
        kept = self.dear and k == 0 and unit.keep
        sock, self.kept = (self.kept, None) if kept else (None, self.kept)
        if kept and self.pace is not None:
            self.pace.batch_started(len(unit.cases))
        led = self._led(k, unit, sock is None)
        flight: Flying
        if self.frames_as_is and self.connect is Flight and plain(unit, led, kept, self.fin_waits):
            flight = single(self.poller.ep, self.host, self.ports[k], unit, led, self.deadline, self.fin_waits)
        else:
            flight = self.connect(
                self.host, self.ports[k], self.adapt(unit.session(lead=led, kept=kept)), self.deadline, sock=sock
            )
        self.log.append(flight)
        q = self.flights[k]
        behind = bool(q)
        if behind:
            flight.deadline = q[-1].flight.deadline + flight.budget  # its turn comes after the one before it
        self._share_allowances(k, flight)
        self.gates[k].connected(flight.started, behind)
        e = InFlight(flight, unit, k, behind, kept, led, flight.started)
        if not unit.tries:  # a unit that runs again is already there
            self.recent.append(e)
        return e

    def _share_allowances(self, k: int, flight: Flying) -> None:
        """A target may serve its ports one at a time: a unit's allowance for its size (a big document takes
        seconds to parse) is added to the deadlines of the units in flight on the other ports (up to
        ``SHARED_UNITS`` allowances each), and theirs to its deadline."""
        now = time.monotonic()
        mine = max(0.0, flight.budget - self.deadline)
        for j, run in enumerate(self.runs):
            if run is not None and j != k and run.flying:
                flight.deadline += run.lend(mine)
        for j, q in enumerate(self.flights):
            for e in q if j != k else ():
                if not e.flight.done:
                    flight.deadline += max(0.0, min(e.flight.deadline - now, e.flight.budget - self.deadline))
                    grant(e, mine)

    # ------------------------------------------------------------------ a finished flight
    def _done(self, e: InFlight, judge_unit: Judge) -> None:
        now = time.monotonic()
        f, unit, gate = e.flight, e.unit, self.gates[e.port]
        # on the kept connection, too, nothing back means the unit was not served (the connection is gone)
        if type(f) is Single or type(f) is CSingle:  # a plain single
            v = f.verdict()
        else:
            v = judge(f.out, unit.owed(f.session, len(f.expected)), e.led or e.kept, unit.keep)
        e.verdict = v
        if e.kept and f.kept is not None:
            self.kept = f.kept
        if v.kind == NOT_ADMITTED:
            self._not_admitted(e, v, now)
            return
        gate.admitted(e.started, e.behind)
        gate.ended(now, admitted=True, behind=e.behind)
        self.live.admitted(e.port, now)
        self.served += 1
        self._may_go_unled()
        if self.pace is not None and e.port and not unit.keep:
            self.pace.single_served()
        if not judge_unit(e, v):
            self.stop = True

    def _may_go_unled(self) -> None:
        """Units that owe nothing may go without the lead once ``WARMUP`` were served and none was turned away."""
        self.unled = self.served >= WARMUP and not self.unled_ever_off

    def _not_admitted(self, e: InFlight, v: Verdict, now: float) -> None:
        """Not served: back to the front of the queue, gated; the lead comes back for good."""
        gate, unit = self.gates[e.port], e.unit
        pipelining = gate.pipelining
        gate.ended(now, admitted=False, behind=e.behind)
        if pipelining and not gate.pipelining:
            self.turned_away = unit.describe()
        unit.tries += 1
        self.unled, self.unled_ever_off = False, True
        if v.how == "timed-out":
            unit.pin = e.port
        self.live.turned_away(e.port, v.how, now)
        self.todo.appendleft(unit)
        self._look_at_liveness(now)

    # ------------------------------------------------------------------ plain singles in bulk (``_singles.Run``)
    def _bulk(self) -> bool:
        """Whether a port's plain singles may run in C: built, real flights, our FIN waits for nothing."""
        return self.bulk and Run is not None and self.connect is Flight and self.frames_as_is and not self.fin_waits

    def _look_at_liveness(self, now: float) -> None:
        gone = self.live.verdict(now)
        if gone is not None:
            self.gone, self.stop = gone, True
            return
        port = self.live.stuck(now)
        if port is None:
            port = next((k for k, t in self.live.failing_since.items() if now - t >= self.patience), None)
            if port is not None:  # the other ports have had nothing to do: ask them, once the flights ran out
                self.suspect, self.stop = port, True
            return
        self.gone, self.stuck, self.stop = "stall", port, True

    def left_unanswered(self, k: int | None) -> Unit | None:
        """The unit that port ``k`` left unanswered (it waits, pinned there, to run again): what stalled a stuck
        port, whether or not other units pushed it out of ``recent`` meanwhile."""
        if k is None:
            return None
        return next((u for u in self.todo if u.pin == k), None)

    def _check_suspect(self) -> None:
        """One port has not served us for ``patience``: a stall when another one serves us now."""
        port, self.suspect = self.suspect, None
        assert port is not None
        for k in range(len(self.ports)):
            if k != port and self.alone(k, Unit([]), patience=self.deadline) is not None:
                self.gone, self.stuck = "stall", port
                return
        self.gone = self.live.verdict(time.monotonic() + self.patience) or "hang"

    # ------------------------------------------------------------------ alone, outside the lanes
    def alone(
        self, k: int, unit: Unit, patience: float | None = None, deadline: float | None = None
    ) -> InFlight | None:
        """Run ``unit`` alone on port ``k`` once the port is free (a replay, a check): turned away, it runs again
        after the backoff; None when the port did not admit it within ``patience``. ``deadline``: the reply
        deadline of this run (default: the campaign's)."""
        self.release()
        end = time.monotonic() + (self.patience if patience is None else patience)
        gate = self.gates[k]
        while True:
            now = time.monotonic()
            if now < gate.retry_at:
                time.sleep(gate.retry_at - now)
            session = self.adapt(unit.session())
            flight = self.connect(self.host, self.ports[k], session, deadline or self.deadline, sock=None)
            self.log.append(flight)
            e = InFlight(flight, unit, k, False, False, True, flight.started)
            fly([flight])
            v = judge(flight.out, unit.owed(flight.session, len(flight.expected)), True, unit.keep)
            e.verdict = v
            now = time.monotonic()
            if v.kind != NOT_ADMITTED:
                gate.admitted(e.started, False)
                gate.ended(now, admitted=True, behind=False)
                self.live.admitted(k, now)
                return e
            gate.ended(now, admitted=False, behind=False)
            if now >= end:
                self.live.turned_away(k, v.how, now)
                return None

    def sent(self) -> list[Session]:
        """What the target was sent lately, in the order it was written, as sessions to replay one after the
        other (``pltf.fuzz.sent``)."""
        return segments((f.session, f.data, f.sends) for f in self.log)

    def release(self) -> None:
        """Give the kept connection back in order (our end-of-stream, the target's close)."""
        sock, self.kept = self.kept, None
        if sock is None:
            return
        with contextlib.suppress(OSError):
            sock.shutdown(socket.SHUT_WR)
            sock.settimeout(self.deadline)
            while sock.recv(1 << 16):
                pass
        sock.close()
        self.gates[0].free_since = time.monotonic()

    def drain(self) -> None:
        """Let the flights in flight run out (unjudged); the ports are then free."""
        fly([e.flight for q in self.flights for e in q])
        for q in self.flights:
            q.clear()
        self.in_bulk.halt()
        runs = [r for r in self.runs if r is not None]
        while True:
            for r in runs:
                r.take()  # taken as they end: poll() waits for the others meanwhile
            if not any(r.flying for r in runs):
                break
            self.poller.step([], until=None)
        self.runs = [None] * len(self.ports)

    def close(self) -> None:
        self.drain()
        self.release()


def _as_is(session: Session) -> Session:
    return session


def _restart_clocks(q: collections.deque[InFlight]) -> None:
    """A port's flight is done: the deadline of each one waiting behind it runs from now, in its turn."""
    t = time.monotonic()
    for e in q:
        t += e.flight.budget
        e.flight.deadline = t


__all__ = ["DONE", "STOPPED", "InFlight", "Lanes", "session_deadline"]
