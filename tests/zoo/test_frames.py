"""frames.FrameCutter against the byte-exact vectors of fixtures/vectors: whole, split at every offset, coalesced,
and a stream out of step passed on unchanged."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pltf.zoo.frames import FrameCutter, Piece

VECTORS = Path(__file__).resolve().parents[2] / "fixtures" / "vectors"
FRAMES = [
    bytes.fromhex(v["hex"])
    for name in ("requests.json", "replies.json")
    for v in json.loads((VECTORS / name).read_text(encoding="utf-8"))
]


def cut(chunks: list[bytes]) -> list[Piece]:
    c = FrameCutter()
    return [p for chunk in chunks for p in c.feed(chunk)] + c.flush()


def test_every_vector_whole_and_coalesced() -> None:
    assert [p.data for p in cut(FRAMES)] == FRAMES
    assert all(p.frame for p in cut([b"".join(FRAMES)]))
    assert [p.data for p in cut([b"".join(FRAMES)])] == FRAMES


@pytest.mark.parametrize("frame", FRAMES[:12])
def test_split_at_every_offset(frame: bytes) -> None:
    for i in range(1, len(frame)):
        pieces = cut([frame[:i], frame[i:]])
        assert [(p.data, p.frame) for p in pieces] == [(frame, True)]
        assert pieces[0].ident == frame[8]


def test_a_stream_out_of_step_passes_unchanged() -> None:
    good, bad = FRAMES[0], bytes.fromhex("deadbeef0000000112")
    pieces = cut([good + bad[:3], bad[3:], good])
    assert [p.frame for p in pieces] == [True, False, False, False]
    assert b"".join(p.data for p in pieces) == good + bad + good
    assert cut([b"\xff\x01\xfe\x02\xff\xff\xff\xff"])[0].frame is False  # a length over the codec's maximum


def test_a_partial_frame_at_the_end_is_flushed_raw() -> None:
    pieces = cut([FRAMES[0][:5]])
    assert [(p.data, p.frame) for p in pieces] == [(FRAMES[0][:5], False)]
