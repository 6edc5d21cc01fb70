"""A unit in flight on a port, as the lanes and the campaign's judge see it. No sockets.

Rules:
- ``InFlight`` pairs a flight (``pltf.fuzz.flight.Flight``, or a plain single: ``pltf.fuzz.single``) with its unit,
  its port and how it was started (pipelined behind another, on the kept connection, led), and carries its verdict
  once judged and the deadline allowances it got from units on the other ports (``pltf.fuzz.lanes``).
- ``Judge`` takes one admitted unit and its verdict and says whether the campaign goes on; ``JudgeClean`` takes the
  admitted plain singles a run of them finished clean, in their order, at once (``pltf.fuzz.runs``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from pltf.fuzz.single import Flying
from pltf.fuzz.unit import Unit
from pltf.fuzz.verdict import Verdict


@dataclass(eq=False, slots=True)
class InFlight:
    flight: Flying
    unit: Unit
    port: int  # index into the ports
    behind: bool  # connected while another unit of ours was on the port (pipelined)
    kept: bool  # on the kept batch connection
    led: bool  # the session opens with the lead
    started: float
    verdict: Verdict | None = None
    shared: float = 0.0  # s added to its deadline for units started on other ports since it started
    largest: float = 0.0  # the largest such allowance


Judge = Callable[[InFlight, Verdict], bool]
JudgeClean = Callable[[list[InFlight]], None]  # admitted plain singles with clean verdicts (``e.verdict``), in order


SHARED_UNITS = 2  # allowances of units started on other ports that a unit in flight gets at most (``grant``)


def grant(e: InFlight, mine: float) -> None:
    """A unit with an allowance of ``mine`` s (for its size) started on another port: ``e``'s deadline moves on by
    it, up to ``SHARED_UNITS`` times the largest such allowance in all (a target that serves its ports in turn comes
    back to ``e`` after one of them; unbounded, batch after batch would push a stalled unit's deadline on for as long
    as they come, and the stall would never show)."""
    e.largest = max(e.largest, mine)
    more = max(0.0, min(mine, SHARED_UNITS * e.largest - e.shared))
    e.flight.deadline += more
    e.shared += more
