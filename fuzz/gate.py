"""One port of the target as the fuzzer sees it: when our next client may connect, whether clients may wait
pipelined behind the one it serves, and what a connection costs there. No sockets, no clock (``now`` comes in).

Rules:
- PlatformCtrl serves one client per port (guide 6.1); what becomes of the next one is left open (erratum
  E-WIRE-007): the reference server reads what its client sent and then takes the newcomer (or closes it at
  once), another implementation leaves it in the listen backlog until the first has gone, a proxy in front of
  one frees the port only milliseconds after its client left and turns newcomers away until then.
- A newcomer that was not admitted (``pltf.fuzz.verdict``) runs again, alone, after a backoff that grows from
  ``BACKOFF_FIRST`` by ``BACKOFF_GROWTH`` up to ``BACKOFF_MAX`` and starts over with the next admission.
- Pipelining (up to ``DEPTH`` units connected on a port at once, the later ones waiting for their turn) stays on
  while newcomers behind a client are served; once ``PIPELINE_TURN_AWAYS`` pipelined units (and more than one
  in twenty) were turned away it stops on that port.
- A port is *dear* when a fresh connection right after our last one has left is turned away more often than not
  (``DEAR_SHARE``; counted, not timed: a loaded machine stretches every wait): the target frees a port only
  some time after its client left. The campaign then keeps a connection for its batches and spends fresh ones
  on the cases that need them. ``release`` is the median wait from our client's end to the next admission.
"""

from __future__ import annotations

import collections

BACKOFF_FIRST = 0.001  # s
BACKOFF_GROWTH = 1.6
BACKOFF_MAX = 0.016  # s: a turned-away newcomer tries again at least this often
DEPTH = 4  # units in flight per port when pipelining: the one served and up to three behind it
PIPELINE_TURN_AWAYS = 3
DEAR_SHARE = 0.5  # of the fresh connections turned away at least once above which a port is dear
SAMPLES = 64  # waits kept for the median


class Gate:
    def __init__(self, index: int, pipelining: bool) -> None:
        self.index = index
        self.pipelining = pipelining
        self.backoff = 0.0
        self.retry_at = 0.0  # no connection of ours before this time
        self.free_since: float | None = None  # when our last client on the port ended (None: none yet)
        self.admissions = 0  # admitted connections that were alone on the port
        self.late = 0  # of them, those admitted only after a turn-away
        # recent waits from the port's last client's end to an admitted connect
        self.waits: collections.deque[float] = collections.deque(maxlen=SAMPLES)
        self.turn_aways = 0
        self.pipelined = 0
        self.pipelined_turned_away = 0

    def may_connect(self, now: float) -> bool:
        return now >= self.retry_at

    def connected(self, now: float, behind: bool) -> None:
        """Our client connects now (``behind``: pipelined behind another of ours)."""
        if behind:
            self.pipelined += 1

    def admitted(self, started: float, behind: bool) -> None:
        """A client of ours that connected at ``started`` was served."""
        if not behind and self.free_since is not None:
            self.admissions += 1
            self.late += self.backoff > 0
            self.waits.append(max(0.0, started - self.free_since))
        self.backoff = 0.0

    def served(self, started: float, behind: bool, end: float) -> None:
        """``admitted`` and ``ended`` of a client that was served, at once (the lanes' plain singles in bulk)."""
        if not behind and self.free_since is not None:
            self.admissions += 1
            self.late += self.backoff > 0
            self.waits.append(max(0.0, started - self.free_since))
        self.backoff = 0.0
        self.free_since = end

    def ended(self, now: float, admitted: bool, behind: bool) -> None:
        """A client of ours is done on the port; not ``admitted``: it was turned away, runs again later."""
        self.free_since = now if admitted or self.free_since is None else self.free_since
        if admitted:
            return
        self.turn_aways += 1
        if behind:
            self.pipelined_turned_away += 1
            if self.pipelined_turned_away >= PIPELINE_TURN_AWAYS and self.pipelined_turned_away * 20 > self.pipelined:
                self.pipelining = False
        self.backoff = BACKOFF_FIRST if not self.backoff else min(BACKOFF_MAX, self.backoff * BACKOFF_GROWTH)
        self.retry_at = now + self.backoff

    @property
    def release(self) -> float:
        """Median seconds from our client's end to the next admission (the port's cost beyond its work)."""
        return sorted(self.waits)[len(self.waits) // 2] if self.waits else 0.0

    @property
    def dear(self) -> bool:
        return self.admissions >= 4 and self.late > DEAR_SHARE * self.admissions
