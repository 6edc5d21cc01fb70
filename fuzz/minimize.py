"""Delta debugging (Zeller's ddmin) over a sequence, bounded in tests and in time.

Rules: ``test(candidate)`` is True when the failure still happens. ``ddmin`` returns a 1-minimal subsequence
when the budget allows (removing any single item makes the failure go away), else the smallest failing
sequence found so far. Results of identical candidates are cached. ``shortest_failing_prefix`` bisects first:
frames are processed in order, so the culprit usually ends the shortest failing prefix.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Hashable, Sequence
from typing import Generic, TypeVar

T = TypeVar("T", bound=Hashable)


def ddmin(
    items: Sequence[T], test: Callable[[list[T]], bool], max_tests: int = 200, max_seconds: float = 60.0
) -> list[T]:
    """Zeller's delta debugging: a 1-minimal failing subsequence, within ``max_tests`` tests and ``max_seconds``."""
    check = _Checker(test, max_tests, time.monotonic() + max_seconds)
    current = list(items)
    n = 2
    while len(current) >= 2 and not check.spent():
        size = len(current)
        chunks = [current[size * k // n : size * (k + 1) // n] for k in range(n)]
        reduced = _first_failing(chunks, size, check)  # each chunk alone
        if reduced is not None:
            current, n = reduced, 2
            continue
        complements = [[x for j, c in enumerate(chunks) if j != k for x in c] for k in range(n)]
        reduced = _first_failing(complements, size, check)
        if reduced is not None:
            current, n = reduced, max(n - 1, 2)
        elif n >= size:
            break
        else:
            n = min(size, 2 * n)
    return current


class _Checker(Generic[T]):
    """The test, cached by candidate, and its budget of tests and time."""

    def __init__(self, test: Callable[[list[T]], bool], max_tests: int, deadline: float) -> None:
        self.test, self.max_tests, self.deadline = test, max_tests, deadline
        self.cache: dict[tuple[T, ...], bool] = {}
        self.tests = 0

    def spent(self) -> bool:
        return self.tests >= self.max_tests or time.monotonic() > self.deadline

    def __call__(self, candidate: list[T]) -> bool:
        key = tuple(candidate)
        if key not in self.cache:
            if self.spent():
                return False
            self.tests += 1
            self.cache[key] = self.test(candidate)
        return self.cache[key]


def _first_failing(candidates: list[list[T]], size: int, check: _Checker[T]) -> list[T] | None:
    """The first non-empty candidate smaller than ``size`` that still fails."""
    for candidate in candidates:
        if candidate and len(candidate) < size and check(candidate):
            return candidate
    return None


def shortest_failing_prefix(items: Sequence[T], test: Callable[[list[T]], bool]) -> list[T]:
    """The shortest prefix that still fails, by bisection (log2 n tests). A target processes a connection's
    frames in order, so the frame that kills it ends the shortest failing prefix; ddmin then has little left
    to do. Assumes ``items`` fails; a property that is not monotone in the prefix only costs tests."""
    lo, hi = 0, len(items)  # prefix of length hi fails; of length lo is assumed not to
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if test(list(items[:mid])):
            hi = mid
        else:
            lo = mid
    return list(items[:hi])
