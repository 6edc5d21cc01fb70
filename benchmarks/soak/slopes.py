"""The soak's verdicts: least-squares slopes per process after the warm-up, each against its bound.

Rules:
- A series is ``[(t_seconds, value), ...]`` of one process and one quantity. Its slope is the least-squares line
  through the samples taken at or after ``warmup`` seconds, in units per HOUR; fewer than three such samples give
  no slope (None): a process that came and went is not judged.
- ``BOUNDS`` is the table of stated bounds (per hour of wall time after the warm-up): a slope within its bound
  passes. Pure functions: no clock, no /proc.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

HOUR = 3600.0
# quantity: (unit per hour, bound per hour). RSS: issue 32's example bound; descriptors and threads: flat (a leak of
# one per connection, with a client that reconnects every few seconds, would be hundreds per hour)
BOUNDS: dict[str, tuple[str, float]] = {
    "rss_mb": ("MB/hour", 1.0),
    "fds": ("fds/hour", 1.0),
    "threads": ("threads/hour", 1.0),
}


@dataclass(frozen=True)
class Slope:
    quantity: str
    per_hour: float
    samples: int
    first: float  # the value at the first sample after the warm-up
    last: float

    @property
    def bound(self) -> float:
        return BOUNDS[self.quantity][1]

    @property
    def unit(self) -> str:
        return BOUNDS[self.quantity][0]

    @property
    def within(self) -> bool:
        return self.per_hour <= self.bound


def least_squares(points: Sequence[tuple[float, float]]) -> float:
    """The slope of the least-squares line through ``points`` (value per unit of t)."""
    n = len(points)
    mt = sum(t for t, _ in points) / n
    mv = sum(v for _, v in points) / n
    stt = sum((t - mt) ** 2 for t, _ in points)
    if stt == 0:
        return 0.0
    return sum((t - mt) * (v - mv) for t, v in points) / stt


def slope(quantity: str, series: Sequence[tuple[float, float]], warmup: float) -> Slope | None:
    kept = [(t, v) for t, v in series if t >= warmup]
    if len(kept) < 3:
        return None
    return Slope(quantity, least_squares(kept) * HOUR, len(kept), kept[0][1], kept[-1][1])
