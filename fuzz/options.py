"""What a campaign is asked to do (``Options``, from the command line) and what it counts (``Stats``: the live
view, ``summary.json``)."""

from __future__ import annotations

import collections
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pltf.fuzz.schedule import BIG_SHARE


@dataclass
class Options:
    host: str
    port: int
    second_port: int
    duration: float
    seed: int
    out: Path
    corpus: Path | None = None
    allow_motion: bool = False
    launch: str | None = None
    max_cases: int | None = None
    max_findings: int | None = None
    deadline: float = 2.0
    minimize_seconds: float = 60.0
    probe_every: int = 4  # after the warm-up, one unit in so many on a port keeps its lead (1: every unit; fuzz.lanes)
    lanes: int = 2  # 2: units run in two lanes, one per port (fuzz.lanes); 1: one at a time on --target's port
    big_share: float = BIG_SHARE  # of the cases over 1 MiB drawn that are kept (fuzz.schedule; 1: natural mix)
    pipeline: bool = True  # a port's next small unit connects while its previous one is in flight (fuzz.gate)
    command: str = "pltf fuzz"


@dataclass
class Stats:
    started: float = field(default_factory=time.monotonic)
    cases: int = 0
    units: int = 0
    batches: int = 0
    singles: int = 0
    probes: int = 0  # units whose lead was answered (each one a liveness probe)
    restarts: int = 0
    cut_replies: int = 0
    dropped_unsafe: int = 0
    skipped: int = 0  # singles skipped on a dear target (fresh connections are what it has least of)
    not_admitted: int = 0  # connections the target did not serve (turned away, backlog): run again
    replays: int = 0  # replays of suspicions
    pipelined: int = 0
    turn_aways: int = 0  # ports on which pipelining stopped: the target turned pipelined newcomers away
    turned_away: list[str] = field(default_factory=list)  # the cases of the unit that showed it
    release_ms: list[float] = field(default_factory=list)  # per port: mean wait for a fresh connection
    dear: bool = False
    ways: dict[str, float] = field(default_factory=dict)  # cases/s each way in the trial (fuzz.trial)
    duplicates: int = 0
    origins: collections.Counter[str] = field(default_factory=collections.Counter)
    telegrams: set[str] = field(default_factory=set)
    states: set[tuple[str, int | None]] = field(default_factory=set)
    state_targets: int = 0
    profile: dict[str, Any] = field(default_factory=dict)  # what the opening phase learnt (fuzz.profile)
    findings: list[dict[str, Any]] = field(default_factory=list)
    unconfirmed: list[dict[str, Any]] = field(default_factory=list)

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self.started

    @property
    def rate(self) -> float:
        return self.cases / self.elapsed if self.elapsed > 0 else 0.0

    @property
    def retried(self) -> int:
        return self.not_admitted
