"""The kept connection's pace: its batches take turns with the singles on the other port. No sockets, no clock.

Rules:
- On the dear way (``pltf.fuzz.lanes``) batches run on a kept connection of port 0 while the *singles* - the
  cases that need a connection of their own: refused ids, torn frames, lying lengths - run on fresh connections
  of the other port. Where the target admits every newcomer in turn (a backlog, erratum E-WIRE-007) a fresh
  connection is work for the target - an accept, a relay's upstream connect, a close - done by the same thread
  that works through the batches. Unpaced, the batches came one after the other and held the other port's
  singles to 0.1-0.26 of the fresh way's (the zoo's ``accept-once`` in front of the reference server).
- Turns: a batch of n cases owes the other ports ``singles(n)`` = ceil(``TURN`` * n) singles. The next batch
  starts only once they were served - those served while the batch ran count too - or when none waits (no
  single queued for another port or in flight there). So the singles keep at least ``TURN`` per batched case
  whatever the machine's load, and a batch never waits for singles that are not there.
- A window queues as many singles as its batches will owe, at least ``pltf.fuzz.engine.SINGLES_QUEUE``; the rest
  of its singles are skipped (counted), the rarest telegrams kept (``pltf.fuzz.unit.rarest_cases``).
- Only the trial's dear way is paced (``pltf.fuzz.trial``: the target turns nobody away). A target that turns
  newcomers away (the zoo's ``slow-release``) is dear by necessity and not paced: there a fresh connection costs
  the target's release time, idle, which the batches do not lengthen; pacing would only slow the batches to
  the trickle of fresh connections such a target gives.
- The bound of the kept way: its singles have one port where fresh connections have two, so where the chain
  of a connection (not the target's CPU) sets the singles' rate it serves at most about half of the fresh
  way's singles per second, the trial's floor (``SINGLES_KEPT``). Measured against ``accept-once`` at load 6-8
  (benchmarks/results/zoo.md): paced, 0.33-0.58 of the fresh way's singles (unpaced 0.1-0.26) at 0.65-1.1 times
  its rate.
"""

from __future__ import annotations

import math

TURN = 0.35  # singles owed per case of a batch on the kept connection


class Pace:
    def __init__(self, turn: float = TURN) -> None:
        self.turn = turn
        self.owed = 0  # singles the kept connection's last batch still waits for
        self.batches = 0  # batches started

    def singles(self, cases: int) -> int:
        """The singles a batch of ``cases`` cases owes the other ports."""
        return math.ceil(self.turn * cases)

    def batch_started(self, cases: int) -> None:
        """A batch of ``cases`` cases starts on the kept connection: it owes its singles from now."""
        self.batches += 1
        self.owed = self.singles(cases)

    def single_served(self) -> None:
        """A single was served on another port."""
        self.owed = max(0, self.owed - 1)

    def ready(self, singles_waiting: bool) -> bool:
        """Whether the next batch may start: the singles owed were served, or none waits (``singles_waiting``:
        singles queued for another port or in flight there)."""
        return self.owed <= 0 or not singles_waiting
