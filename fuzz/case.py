"""A fuzz case: the frames sent on one connection, how they are delivered, and where they came from.

Rules:
- ``frames`` are the units delta debugging removes (usually one telegram frame each; a raw fragment when
  a mutation cut across frames). The bytes on the wire are their concatenation.
- ``delivery`` says how the bytes are written: ``whole`` (one write), ``bytewise`` (one write per byte) or
  ``slow`` (``pieces`` writes ``pause`` seconds apart). It is derived from the bytes, so it survives the
  removal of frames during minimization.
- ``half_close`` shuts our sending side after the last byte (the peer reads end-of-stream).
- Cases are plain data: a JSON round trip (``to_json``/``from_json``) is how the corpus and the findings keep
  them.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass, field, replace
from typing import Any

MAX_PAUSE_TOTAL = 0.05  # s: a slow case never takes longer than this to send


@dataclass(frozen=True)
class Delivery:
    mode: str = "whole"  # whole | bytewise | slow
    pieces: int = 1
    pause: float = 0.0

    def chunks(self, data: bytes) -> list[tuple[bytes, float]]:
        """(bytes, pause before them) in sending order."""
        if self.mode == "bytewise":
            return [(data[i : i + 1], 0.0) for i in range(len(data))]
        if self.mode == "slow" and self.pieces > 1 and len(data) > 1:
            n = min(self.pieces, len(data))
            pause = min(self.pause, MAX_PAUSE_TOTAL / n)
            cuts = [len(data) * k // n for k in range(n + 1)]
            return [(data[a:b], pause if k else 0.0) for k, (a, b) in enumerate(itertools.pairwise(cuts))]
        return [(data, 0.0)]


WHOLE = Delivery()


@dataclass(frozen=True)
class Case:
    frames: tuple[bytes, ...]
    origin: str  # generator or mutator, e.g. "gen.hostile", "mut.length_lie", "xml.billion_laughs"
    telegram: str  # the telegram the case is about ("id 66" for an id without a telegram)
    note: str = ""  # what was done, e.g. "frames.count=-1"
    delivery: Delivery = WHOLE
    half_close: bool = False
    expect: str = ""  # fuzz.wire.KEEP / CLOSE / PARTIAL, filled by the scheduler
    tags: tuple[str, ...] = field(default=())
    answered: tuple[int, ...] | None = None  # ids of the answered requests in the frames (fuzz.wire.survey)

    @property
    def data(self) -> bytes:
        return b"".join(self.frames)

    @functools.cached_property
    def size(self) -> int:  # asked for several times per case by the lanes: computed once
        return sum(map(len, self.frames))

    def judged(self, expect: str, answered: tuple[int, ...]) -> Case:
        """The case with what a strict server does with it (``dataclasses.replace`` without its field walk: one
        per case drawn)."""
        new = object.__new__(Case)
        new.__dict__.update(self.__dict__, expect=expect, answered=answered)
        return new

    def with_frames(self, frames: tuple[bytes, ...]) -> Case:
        return replace(self, frames=frames, answered=None)

    def to_json(self) -> dict[str, Any]:
        return {
            "frames": [f.hex() for f in self.frames],
            "origin": self.origin,
            "telegram": self.telegram,
            "note": self.note,
            "delivery": {"mode": self.delivery.mode, "pieces": self.delivery.pieces, "pause": self.delivery.pause},
            "half_close": self.half_close,
            "expect": self.expect,
        }

    @classmethod
    def from_json(cls, obj: dict[str, Any]) -> Case:
        d = obj.get("delivery") or {}
        return cls(
            frames=tuple(bytes.fromhex(h) for h in obj["frames"]),
            origin=obj.get("origin", "corpus"),
            telegram=obj.get("telegram", "?"),
            note=obj.get("note", ""),
            delivery=Delivery(d.get("mode", "whole"), int(d.get("pieces", 1)), float(d.get("pause", 0.0))),
            half_close=bool(obj.get("half_close", False)),
            expect=obj.get("expect", ""),
        )
