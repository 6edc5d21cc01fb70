"""schedule.py: due times keep the stream's order, pieces due together leave together, the front of a chunk is
torn into small writes."""

from __future__ import annotations

import random

from pltf.zoo.frames import Piece
from pltf.zoo.schedule import SMALL_PIECES, ReplySchedule, for_ident, jitter, segments

STATUS = Piece(bytes.fromhex("ff01fe0200000001") + bytes([18]), True)
POSITION = Piece(bytes.fromhex("ff01fe0200000001") + bytes([74]), True)


def test_one_late_reply_holds_back_the_ones_behind_it() -> None:
    s = ReplySchedule(for_ident(18, 12.0), random.Random(1))
    assert s.push(STATUS, 0.0) == 12.0
    assert s.push(POSITION, 0.5) == 12.0  # not before the status reply ahead of it
    assert s.due(11.9) == b"" and s.next_due == 12.0
    assert s.due(12.0) == STATUS.data + POSITION.data and len(s) == 0  # due together, leave together


def test_jitter_stays_in_its_bounds_and_in_order() -> None:
    s = ReplySchedule(jitter(0.05, 0.2), random.Random(7))
    dues = [s.push(POSITION, t * 0.001) for t in range(200)]
    assert dues == sorted(dues)
    assert all(d - t * 0.001 >= 0.05 for t, d in enumerate(dues)) and dues[0] <= 0.2


def test_segments_tear_the_front_and_keep_every_byte() -> None:
    rng = random.Random(3)
    chunk = bytes(range(200))
    parts = segments(chunk, rng, 7)
    assert b"".join(parts) == chunk
    assert len(parts) == SMALL_PIECES + 1 and all(1 <= len(p) <= 7 for p in parts[:-1])
    assert segments(chunk, rng, 0) == [chunk] and segments(b"", rng, 7) == []
