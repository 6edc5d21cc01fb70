"""Delta debugging (Zeller's ddmin) over a sequence, bounded in tests and in time.

Rules: ``test(candidate)`` is True when the failure still happens. ``ddmin`` returns a 1-minimal subsequence
when the budget allows (removing any single item makes the failure go away), else the smallest failing
sequence found so far. Results of identical candidates are cached. ``shortest_failing_prefix`` bisects first:
frames are processed in order, so the culprit usually ends the shortest failing prefix.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Hashable, Sequence
from typing import TypeVar

T = TypeVar("T", bound=Hashable)


def ddmin(
    items: Sequence[T], test: Callable[[list[T]], bool], max_tests: int = 200, max_seconds: float = 60.0
) -> list[T]:
    current = list(items)
    cache: dict[tuple[T, ...], bool] = {}
    deadline = time.monotonic() + max_seconds
    tests = 0

    def check(candidate: list[T]) -> bool:
        nonlocal tests
        key = tuple(candidate)
        if key not in cache:
            if tests >= max_tests or time.monotonic() > deadline:
                return False
            tests += 1
            cache[key] = test(candidate)
        return cache[key]

    n = 2
    while len(current) >= 2:
        size = len(current)
        chunks = [current[size * k // n : size * (k + 1) // n] for k in range(n)]
        reduced = False
        for chunk in chunks:  # try each chunk alone
            if chunk and len(chunk) < size and check(chunk):
                current, n, reduced = chunk, 2, True
                break
        if not reduced:
            for k in range(n):  # try each complement
                complement = [x for j, c in enumerate(chunks) if j != k for x in c]
                if complement and len(complement) < size and check(complement):
                    current, n, reduced = complement, max(n - 1, 2), True
                    break
        if not reduced:
            if n >= size:
                break
            n = min(size, 2 * n)
        if tests >= max_tests or time.monotonic() > deadline:
            break
    return current


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
