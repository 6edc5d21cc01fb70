"""Which way to run a target that turns no newcomer away: a fresh connection per unit (pipelined), or the dear
way (batches on one kept connection, fresh connections only for the cases that need them). Measured, not
guessed. No sockets, no clock (the seconds come in).

Rules:
- A target that turns newcomers away is dear by necessity (``pltf.fuzz.gate``): no trial.
- Otherwise, after ``WARMUP`` windows the campaign runs ``WINDOWS`` windows each way, alternating (a noisy spell
  of the machine hits both), and keeps the dear way only when it served ``GAIN`` times the cases per second:
  the dear way skips singles beyond a queue (``pltf.fuzz.engine``), so it must pay for them. A connection that
  costs little (the reference server: ~0.2 ms) keeps fresh connections; one behind a relay that admits one
  client at a time (a newcomer's connect waits for the last client's whole close) is faster kept.
- A trial's figures are reported (``Stats.ways``): cases per second each way.
"""

from __future__ import annotations

WARMUP = 2  # windows before the trial (the leads of the first units, the first documents)
WINDOWS = 5  # windows measured each way
GAIN = 1.2  # the dear way must serve this many times the cases per second


class Trial:
    def __init__(self) -> None:
        self.seen = 0  # windows recorded, warm-up included
        self.cases = {False: 0, True: 0}
        self.seconds = {False: 0.0, True: 0.0}
        self.decided: bool | None = None

    def settle(self, dear: bool) -> None:
        """No trial: the target decided (it turns newcomers away)."""
        self.decided = dear

    def way(self) -> bool:
        """Dear (True) or fresh connections (False) for the next window."""
        if self.decided is not None:
            return self.decided
        return self.seen >= WARMUP and (self.seen - WARMUP) % 2 == 1

    def record(self, dear: bool, cases: int, seconds: float) -> None:
        """A window ran ``dear`` or not and served ``cases`` in ``seconds``."""
        if self.decided is not None:
            return
        self.seen += 1
        if self.seen <= WARMUP:
            return
        self.cases[dear] += cases
        self.seconds[dear] += seconds
        if self.seen >= WARMUP + 2 * WINDOWS:
            rates = self.rates
            self.decided = rates["dear"] > GAIN * rates["fresh"]

    @property
    def rates(self) -> dict[str, float]:
        """Cases per second each way so far."""
        return {
            name: self.cases[k] / self.seconds[k] if self.seconds[k] > 0 else 0.0
            for name, k in (("fresh", False), ("dear", True))
        }
