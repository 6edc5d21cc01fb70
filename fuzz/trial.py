"""Which way to run a target that turns no newcomer away: a fresh connection per unit (pipelined), or the dear
way (batches on one kept connection, fresh connections only for the cases that need them). Measured, not
guessed. No sockets, no clock (the seconds come in).

Rules:
- A target that turns newcomers away is dear by necessity (``pltf.fuzz.gate``): no trial.
- Otherwise, after ``WARMUP`` windows the campaign runs ``WINDOWS`` windows each way, alternating (a noisy spell
  of the machine hits both), and keeps the dear way only when it served ``GAIN`` times the cases per second
  AND gave up little coverage: the dear way skips singles beyond a queue (``pltf.fuzz.engine``), the cases the
  target should refuse (unknown ids, torn frames, lying lengths: the input classes a stall or a crash hides
  in), so it must also serve at least ``SINGLES_KEPT`` of the singles per second fresh connections serve. The
  rate alone would trade them for the cheap batches: against a target whose connections cost little the kept
  connection serves more cases per second, but a sixth of the singles, and a bug behind a rare id goes unseen.
  A connection that costs little (the reference server: ~0.2 ms) keeps fresh connections; one behind a relay
  that admits one client at a time (a newcomer's connect waits for the last client's whole close) may be
  faster kept.
- The dear way of a trial is paced (``pltf.fuzz.pace``): its batches take turns with the singles of the other
  port. A window of it runs until its batches are done and the singles they owe were served; when the next
  window runs the other way it runs its queued singles out, so that each way is credited with its own cases.
- A trial's figures are reported (``Stats.ways``): cases per second each way, and singles per second each way.
"""

from __future__ import annotations

WARMUP = 2  # windows before the trial (the leads of the first units, the first documents)
WINDOWS = 5  # windows measured each way
GAIN = 1.2  # the dear way must serve this many times the cases per second
SINGLES_KEPT = 0.5  # ... and at least this share of the singles per second of fresh connections


class Trial:
    def __init__(self) -> None:
        self.seen = 0  # windows recorded, warm-up included
        self.cases = {False: 0, True: 0}
        self.singles = {False: 0, True: 0}
        self.seconds = {False: 0.0, True: 0.0}
        self.decided: bool | None = None
        self.settled = False  # decided by the target, not by a trial (the dear way is then not paced)

    def settle(self, dear: bool) -> None:
        """No trial: the target decided (it turns newcomers away)."""
        self.decided, self.settled = dear, True

    def way(self) -> bool:
        """Dear (True) or fresh connections (False) for the next window."""
        if self.decided is not None:
            return self.decided
        return self.seen >= WARMUP and (self.seen - WARMUP) % 2 == 1

    def next_way(self) -> bool:
        """The way of the window after the one running now, as far as it is known (the trial may still decide
        otherwise). A dear window followed by a fresh one runs its singles out: the fresh window would count them."""
        if self.decided is not None:
            return self.decided
        n = self.seen + 1
        return n >= WARMUP and (n - WARMUP) % 2 == 1

    def record(self, dear: bool, cases: int, seconds: float, singles: int = 0) -> None:
        """A window ran ``dear`` or not and served ``cases`` in ``seconds``, ``singles`` of them singles (a case
        on a connection of its own)."""
        if self.decided is not None:
            return
        self.seen += 1
        if self.seen <= WARMUP:
            return
        self.cases[dear] += cases
        self.singles[dear] += singles
        self.seconds[dear] += seconds
        if self.seen >= WARMUP + 2 * WINDOWS:
            rates = self.rates
            faster = rates["dear"] > GAIN * rates["fresh"]
            covers = rates["dear singles"] >= SINGLES_KEPT * rates["fresh singles"]
            self.decided = faster and covers

    @property
    def rates(self) -> dict[str, float]:
        """Cases per second each way so far, and singles per second each way."""
        out = {}
        for name, k in (("fresh", False), ("dear", True)):
            s = self.seconds[k]
            out[name] = self.cases[k] / s if s > 0 else 0.0
            out[f"{name} singles"] = self.singles[k] / s if s > 0 else 0.0
        return out
