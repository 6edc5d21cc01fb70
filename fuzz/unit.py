"""A unit: what one oracle verdict covers, and the session that carries it. No sockets.

Rules:
- A *batch* is cases the strict codec accepts, pipelined on one connection and closed by a GET_STATUS ``sync``
  whose reply proves all of them were processed (the server answers nothing else, erratum E-CMD-013); a
  *single* is one case the target should refuse, or that needs its own delivery.
- A session opens with the *lead* (``pltf.fuzz.target.LEAD``: any byte back, the target took the connection,
  ``pltf.fuzz.verdict``), then the unit's state prelude and its *check* GET_STATUS (``pltf.fuzz.preludes``), then
  the cases; our write side is shut after them (on a kept connection the sync reply ends the unit instead).
- A single whose bytes may not arrive in one piece (over ``PIPELINE_BYTES``, or a slow or bytewise delivery) is
  *gated*: its lead goes alone and the rest waits for the target's first byte, so that a target that closes
  on it with our input unread (a reset) cannot lose the lead's reply - the proof it was served. So is every
  unit that runs again after it was not served: a target that takes in a whole read before it answers anything
  then shows whether the port or the unit kept it silent. A unit left unanswered runs again on the same port
  (``pin``): were it the culprit, it would stall the other port too.
- ``owed``: the replies the target must send (E-WIRE-006): every one of a batch; of a single, those asked before
  its case (the lead, the prelude's, the check) - behind a gate only the lead.
- Where fresh connections are scarce (a dear target) and only some singles of a window can run, ``rarest`` keeps
  those whose telegram (a name, or ``id N`` for an unknown id) ran least so far: every id and telegram comes
  round in turn, none is left to the luck of the draw.
"""

from __future__ import annotations

import collections
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Generic, TypeVar, overload

from pltf.fuzz.case import WHOLE, Case
from pltf.fuzz.preludes import Target, chart_last
from pltf.fuzz.target import GET_STATUS, LEAD, Session
from pltf.fuzz.wire import KEEP, answered_ids
from pltf.spec.codec import REQUESTS

GET_STATUS_ID = REQUESTS.CMD_GET_STATUS.ID
LEAD_ID = LEAD[8]
PIPELINE_BYTES = 1 << 14  # units up to this size may be pipelined on a port (read whole by one recv)
BATCH_CASES = 128
BATCH_BYTES = 1 << 18
T = TypeVar("T")


class once(Generic[T]):
    """``functools.cached_property`` without its lock: Python 3.11 takes an RLock at each first access, and a unit's
    five are each asked for once or more per unit, about half of all units being singles (issue 34)."""

    def __init__(self, fn: Callable[[Any], T]) -> None:
        self.fn, self.name, self.__doc__ = fn, fn.__name__, fn.__doc__

    @overload
    def __get__(self, obj: None, owner: type | None = None) -> once[T]: ...
    @overload
    def __get__(self, obj: object, owner: type | None = None) -> T: ...
    def __get__(self, obj: object | None, owner: type | None = None) -> T | once[T]:
        if obj is None:
            return self
        value = obj.__dict__[self.name] = self.fn(obj)  # the instance's attribute from now on
        return value


def batchable(c: Case) -> bool:
    """A case the strict codec accepts, small and written whole: it goes into a batch."""
    return c.expect == KEEP and c.delivery.mode == "whole" and c.size < BATCH_BYTES // 4


@dataclass(eq=False)
class Unit:
    cases: list[Case]
    prelude: list[bytes] = field(default_factory=list)
    target: Target | None = None  # the plan target its prelude drives to (None: no prelude)
    tries: int = 0  # connections that were not admitted so far
    pin: int | None = None  # the port it must run again on (it was left unanswered there)

    @once
    def keep(self) -> bool:
        """Every case accepted by the strict codec (a unit without cases - a lead alone - is not: it owes only
        the lead's reply). Its cases never change: asked for many times per unit, computed once."""
        return bool(self.cases) and all(c.expect == KEEP for c in self.cases)

    @once
    def batch(self) -> bool:
        return len(self.cases) > 1 or (bool(self.cases) and batchable(self.cases[0]))

    @once
    def size(self) -> int:
        """Asked for a few times per unit, computed once (a unit's prelude is set before: ``window_units``)."""
        return sum(c.size for c in self.cases) + sum(len(f) for f in self.prelude)

    @once
    def whole(self) -> bool:
        """Small and written in one piece: it may wait behind another unit (pipelining)."""
        return self.size <= PIPELINE_BYTES and all(c.delivery.mode == "whole" for c in self.cases)

    @property
    def head(self) -> list[bytes]:
        """The prelude and its check (nothing without a prelude)."""
        return [*self.prelude, GET_STATUS] if self.prelude else []

    @once
    def prelude_ids(self) -> list[int]:
        """The ids of the answered requests of the prelude and its check."""
        return [*answered_ids(b"".join(self.prelude)), GET_STATUS_ID] if self.prelude else []

    @property
    def check_at(self) -> int | None:
        """Index among the replies of a led session of the check's reply (None: no prelude)."""
        return len(self.prelude_ids) if self.prelude else None

    def session(self, lead: bool = True, kept: bool = False) -> Session:
        """The session carrying the unit: on its own connection (``kept`` False) or on a kept one."""
        head = [*([LEAD] if lead else []), *self.head]
        frames = [*head, *(f for c in self.cases for f in c.frames)]
        known = all(c.answered is not None for c in self.cases)
        ids = [*([LEAD_ID] if lead else []), *self.prelude_ids]
        answered = [*ids, *(i for c in self.cases for i in c.answered or ())] if known else None
        delivery = self.cases[0].delivery if self.cases and not self.batch else WHOLE
        gate = lead and (self.tries > 0 or (not self.keep and not self.whole))
        return Session(frames, delivery, half_close=not kept, sync=self.keep, answered=answered, gate=gate, led=lead)

    def owed(self, session: Session, expected: int) -> int:
        """Replies owed in ``session`` (``expected``: the replies it asks for, sync included)."""
        if self.keep:
            return expected
        if session.gate:
            return 1
        return int(session.led) + len(self.prelude_ids)

    def describe(self) -> list[str]:
        return [f"{c.telegram} ({c.origin}{': ' + c.note if c.note else ''})" for c in self.cases[:3]]


def window_units(
    cases: list[Case],
    head: Callable[[], list[bytes]],
    target: Target,
    single_prelude: Callable[[Case], list[bytes]],
    choose: Callable[[list[Case], list[list[Case]]], list[Case]] | None = None,
) -> list[Unit]:
    """A window of cases as units: batches of the ``batchable`` ones (at most ``BATCH_CASES`` cases and
    ``BATCH_BYTES``; chart commands last, ``pltf.fuzz.preludes.chart_last``), the first one behind ``head()``, the
    state prelude to ``target`` (asked for only when there is a batch); a single per other case, behind
    ``single_prelude(case)``; the batches spread evenly among the singles (while the target works through a batch
    on one port, the other carries singles). ``choose(singles, batches)``: the singles' cases that run (a dear
    target: ``rarest_cases``), chosen before any unit is built for them."""
    batches: list[list[Case]] = [[]]
    size = 0
    alone: list[Case] = []
    for c in cases:
        if not batchable(c):
            alone.append(c)
            continue
        if len(batches[-1]) >= BATCH_CASES or size + c.size > BATCH_BYTES:
            batches.append([])
            size = 0
        batches[-1].append(c)
        size += c.size
    groups = [b for b in batches if b]
    if choose is not None:
        alone = choose(alone, groups)
    singles: list[Unit] = []
    for c in alone:
        prelude = single_prelude(c)
        singles.append(Unit([c], prelude, target if prelude else None))
    units = [Unit(chart_last(b)) for b in groups]
    if units:
        units[0].prelude = head()
        units[0].target = target if units[0].prelude else None
    if not units:
        return singles
    out: list[Unit] = []
    step = len(singles) / len(units)
    for i, batch in enumerate(units):
        out.extend(singles[round(i * step) : round((i + 1) * step)])
        out.append(batch)
    return out


def rarest(singles: list[Unit], room: int, seen: collections.Counter[str]) -> list[Unit]:
    """The ``room`` singles (in their order) whose telegrams ran least so far by ``seen``, which counts them:
    the k-th single of a telegram in ``singles`` ranks as if the k - 1 before it had run (a round robin)."""
    return _rarest(singles, room, seen, lambda u: u.cases[0].telegram if u.cases else None)


def rarest_cases(singles: list[Case], room: int, seen: collections.Counter[str]) -> list[Case]:
    """``rarest`` of the singles' cases, before units are built for them (``window_units``' ``choose``)."""
    return _rarest(singles, room, seen, lambda c: c.telegram)


def _rarest(items: list[T], room: int, seen: collections.Counter[str], name: Callable[[T], str | None]) -> list[T]:
    if len(items) > room:
        ahead: collections.Counter[str] = collections.Counter()
        rank = []
        for i, item in enumerate(items):
            t = name(item) or ""
            rank.append((seen[t] + ahead[t], i))
            ahead[t] += 1
        items = [items[i] for i in sorted(i for _, i in sorted(rank)[:room])]
    seen.update(t for t in map(name, items) if t is not None)
    return items
