"""The plain singles of a port in bulk: what the lanes hand to C (``_singles.Run``) and what they take back.

Rules (the lanes' rules hold; this is their bulk path, ``pltf.fuzz.lanes.Lanes.bulk``):
- A port with nothing of Python's on it hands the plain singles it would take next (``plain_unit``; their leads
  decided by the lanes, in their order) to its ``Run``, ``FEED`` waiting at most (``Bulk.feed``). C starts them as
  the lanes would - a fresh connection each, up to the gate's depth behind one that was sent whole and owes only
  the lead, a waiting one's deadline from its turn - drives them on the lanes' epoll and finishes them in port
  order.
- Python takes the finished ones a few at a time (``Bulk.take``): the admitted ones are counted (gate, liveness,
  served, pace) in one loop and the clean ones handed to the campaign at once (``JudgeClean``); only a suspicious
  one is judged alone, and one not admitted goes back to the front of the queue as in the lanes.
- The allowances between the ports (``pltf.fuzz.inflight.grant``) go both ways: the units Python drives
  on the other ports lend theirs to each single a run starts, each single's is granted to them (``Bulk.share``).
- A single not admitted or past its deadline stops its run (C starts nothing more after it); a stop halts every
  run (``Bulk.halt``): the singles a run did not start go back to the front of the queue, in their order, and out
  of the lanes' ``log`` and ``recent`` (``Bulk.give_back``).
"""

from __future__ import annotations

import collections
import time
from typing import TYPE_CHECKING, Any

from pltf.fuzz.inflight import InFlight, Judge, JudgeClean, grant
from pltf.fuzz.single import single
from pltf.fuzz.target import LEAD_IDS
from pltf.fuzz.unit import PIPELINE_BYTES, Unit
from pltf.fuzz.verdict import NOT_ADMITTED, OK
from pltf.fuzz.wire import KEEP

if TYPE_CHECKING:
    from pltf.fuzz._singles import Run
    from pltf.fuzz.lanes import Lanes

FEED = 16  # plain singles waiting in a port's ``Run`` at most (it asks for more when fewer than four wait)


def plain_unit(unit: Unit) -> bool:
    """A unit that runs as a plain single whatever its lead (``pltf.fuzz.single.plain`` when our FIN waits for
    nothing): one case the target should refuse, written whole and small, never turned away."""
    if unit.tries or len(unit.cases) != 1:
        return False
    c = unit.cases[0]
    return c.expect != KEEP and c.delivery.mode == "whole" and c.size + sum(map(len, unit.prelude)) <= PIPELINE_BYTES


class Bulk:
    """The lanes' bulk path: it reads and changes the lanes' queue, gates, liveness and counts."""

    def __init__(self, lanes: Lanes) -> None:
        self.lanes = lanes

    def feed(self, k: int, run: Run) -> None:
        """Hand port ``k``'s run the plain singles it takes next (the lanes' ``_pick``, up to ``FEED`` waiting),
        each made here once (its lead, bytes and budget); the run starts them in their turn."""
        lanes = self.lanes
        todo, pool, host, port, deadline = lanes.todo, lanes.poller.ep, lanes.host, lanes.ports[k], lanes.deadline
        full = False
        while todo:
            if run.waiting >= FEED:
                full = True
                break
            unit = lanes._pick(k)
            if unit is None or not plain_unit(unit):
                break
            if unit is todo[0]:
                todo.popleft()
            else:
                todo.remove(unit)
            led = lanes._led(k, unit, True)
            s: Any = single(pool, host, port, unit, led, deadline, False, start=False)
            chain = len(s.data) <= PIPELINE_BYTES and LEAD_IDS.issuperset(s.expected)
            run.add(s, led, chain, s.budget - deadline)
            lanes.log.append(s)
            s.entry = e = InFlight(s, unit, k, False, False, led, 0.0)
            lanes.recent.append(e)
        run.hungry = full
        run.advance()

    def take(self, k: int, run: Run, judge_unit: Judge, judge_clean: JudgeClean | None) -> None:
        """The singles port ``k``'s run finished, in port order: each judged; the admitted ones counted (gate,
        liveness, served) in one loop and the clean ones handed to ``judge_clean`` at once; a run that stopped
        (a single not admitted, or past its deadline) gives back the singles it did not start."""
        done = run.take()
        if not done:
            return
        lanes = self.lanes
        if run.halted:
            self.give_back(run)
        gate, pace = lanes.gates[k], lanes.pace if k else None
        clean: list[InFlight] = []
        end = None
        for f in done:
            e = f.entry
            e.started, e.behind = f.started, f.behind
            gate.pipelined += f.behind  # ``Gate.connected``
            v = e.verdict = f.verdict()
            if v.kind == NOT_ADMITTED:
                _judge_clean(clean, judge_unit, judge_clean)
                lanes._not_admitted(e, v, time.monotonic())
                continue
            end = f.end_at
            gate.served(f.started, f.behind, end)
            lanes.served += 1
            if pace is not None:
                pace.single_served()
            if v.kind == OK:
                clean.append(e)
                continue
            _judge_clean(clean, judge_unit, judge_clean)
            if not judge_unit(e, v):
                lanes.stop = True
        _judge_clean(clean, judge_unit, judge_clean)
        if end is not None:
            lanes.live.admitted(k, end)
        lanes._may_go_unled()

    def share(self, runs: list[tuple[int, Run]]) -> None:
        """The allowances between the runs' singles and the units Python drives on the other ports (as the lanes'
        ``_share_allowances``): theirs lent to each single started, each single's granted to them."""
        lanes = self.lanes
        for k, run in runs:
            others = [e for j, q in enumerate(lanes.flights) if j != k for e in q if not e.flight.done]
            run.set_others([(e.flight.deadline, max(0.0, e.flight.budget - lanes.deadline)) for e in others])
            for mine in run.new_starts():
                for e in others:
                    grant(e, mine)

    def halt(self) -> None:
        """No run starts anything more; the singles they did not start go back to the queue."""
        for run in self.lanes.runs:
            if run is not None and run.active and not run.halted:
                run.halt()
                self.give_back(run)

    def give_back(self, run: Run) -> None:
        """The singles ``run`` did not start go back to the front of the queue, in their order, and are no longer
        among the units sent (they were not)."""
        back = run.unstarted()
        if not back:
            return
        lanes = self.lanes
        lanes.todo.extendleft(reversed([s.unit for s in back]))
        gone = {id(s) for s in back}
        lanes.recent = collections.deque((e for e in lanes.recent if id(e.flight) not in gone), lanes.recent.maxlen)
        lanes.log = collections.deque((f for f in lanes.log if id(f) not in gone), lanes.log.maxlen)


def _judge_clean(clean: list[InFlight], judge_unit: Judge, judge_clean: JudgeClean | None) -> None:
    """Hand the clean singles gathered to the campaign at once (``judge_unit`` one by one without a
    ``judge_clean``); ``clean`` is then empty."""
    if not clean:
        return
    if judge_clean is not None:
        judge_clean(clean)
    else:
        for e in clean:
            assert e.verdict is not None
            judge_unit(e, e.verdict)
    clean.clear()
