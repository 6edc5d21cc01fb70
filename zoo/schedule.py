"""When the bytes a relay holds for a client are due, and how they are cut into writes (sans-IO).

Rules:
- ``ReplySchedule.push(piece, now)`` gives the piece a due time ``now + delay(piece)`` but never before the one
  pushed before it: the stream keeps its order (TCP), so one late reply holds back the ones behind it.
- ``due(now)`` takes every piece due by ``now`` off the front and joins them into one chunk: replies that became
  due together leave together (coalesced), as a slow link delivers them.
- ``segments(chunk, rng, segment)`` cuts the front of a chunk into small writes (1..``segment`` bytes, random),
  ``SMALL_PIECES`` of them, and the rest into one: a client sees the header of a reply torn across TCP segments
  and the end of one reply in the segment that carries the next (the relay leaves a gap between writes).
- Time is ``now`` (seconds, any monotonic origin) and randomness a seeded ``random.Random``, both passed in.
"""

from __future__ import annotations

import random
from collections import deque
from collections.abc import Callable

from pltf.zoo.frames import Piece

Delay = Callable[[Piece, random.Random], float]
SMALL_PIECES = 8


def no_delay(piece: Piece, rng: random.Random) -> float:
    return 0.0


def jitter(low: float, high: float) -> Delay:
    """A delay drawn uniformly from [low, high] seconds for every piece."""

    def delay(piece: Piece, rng: random.Random) -> float:
        return rng.uniform(low, high)

    return delay


def for_ident(ident: int, seconds: float) -> Delay:
    """``seconds`` for the frames of one telegram identifier, none for the rest."""

    def delay(piece: Piece, rng: random.Random) -> float:
        return seconds if piece.ident == ident else 0.0

    return delay


class ReplySchedule:
    def __init__(self, delay: Delay, rng: random.Random) -> None:
        self.delay = delay
        self.rng = rng
        self._queue: deque[tuple[float, bytes]] = deque()
        self._last_due = float("-inf")

    def push(self, piece: Piece, now: float) -> float:
        due = max(self._last_due, now + self.delay(piece, self.rng))
        self._last_due = due
        self._queue.append((due, piece.data))
        return due

    @property
    def next_due(self) -> float | None:
        return self._queue[0][0] if self._queue else None

    def __len__(self) -> int:
        return len(self._queue)

    def due(self, now: float) -> bytes:
        out = bytearray()
        while self._queue and self._queue[0][0] <= now:
            out += self._queue.popleft()[1]
        return bytes(out)


def segments(chunk: bytes, rng: random.Random, segment: int, pieces: int = SMALL_PIECES) -> list[bytes]:
    """``chunk`` as writes: the first ``pieces`` of 1..``segment`` bytes each (a header torn apart), the rest in
    one write (the whole chunk when ``segment`` is 0)."""
    if segment <= 0 or len(chunk) <= 1:
        return [chunk] if chunk else []
    out: list[bytes] = []
    i = 0
    while i < len(chunk) and len(out) < pieces:
        n = rng.randint(1, segment)
        out.append(chunk[i : i + n])
        i += n
    if i < len(chunk):
        out.append(chunk[i:])
    return out
