"""The compiled drawing core (fuzz/_draw.c): its survey is the codec's, its cases are what they say they are, and
it draws what the Python generators draw (every origin, every telegram, the hostile values, what was learnt)."""

from __future__ import annotations

import collections
import os
import pickle
import random

import pytest

from pltf.fuzz import draw, generate, safety
from pltf.fuzz.case import Case
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.schedule import Scheduler
from pltf.fuzz.wire import CLOSE, forbidden_ids, survey
from pltf.spec.codec import REQUESTS, encode

pytestmark = pytest.mark.skipif(not draw.AVAILABLE and os.environ.get("PLTF_NO_EXTENSIONS") == "1", reason="no C")
MOTION = safety.forbidden(allow_motion=True)
SAFE = safety.forbidden(allow_motion=False)


def test_the_core_is_built() -> None:
    """setup.py builds it with the package (optional: a failed build is a warning), so a test run would otherwise
    pass on the Python stream without anyone noticing."""
    assert draw.AVAILABLE


def _corrupted(data: bytes, rng: random.Random) -> bytes:
    b = bytearray(data)
    for _ in range(rng.choice((1, 2, 3))):
        if b and rng.random() < 0.7:
            b[rng.randrange(len(b))] = rng.choice((0, 1, 0x7F, 0x80, 0xFF, rng.randrange(256)))
        if rng.random() < 0.3:
            b = b[: rng.randrange(len(b) + 1)]
    return bytes(b)


def test_the_compiled_survey_is_the_codecs() -> None:
    """KEEP / CLOSE / PARTIAL and the answered ids, and the forbidden ids, of valid, corrupted and cut streams."""
    rng = random.Random(5)
    sched = Scheduler(2, MOTION, Knowledge(), compiled=False)
    samples = [sched.case(i).data for i in range(1500)]
    samples += [encode(REQUESTS.CMD_GET_STATUS()) * 3 + encode(REQUESTS.CMD_CLOSE_SOCKET()), b"", b"\xff\x01", b"\x00"]
    mask = draw.mask(SAFE)
    kinds = collections.Counter()
    for data in samples:
        for d in (data, _corrupted(data, rng), _corrupted(data, rng)):
            kind, answered = survey(d)
            assert draw.survey(d) == (kind, tuple(answered)), d.hex()
            assert draw._draw.forbidden(d, mask) == bool(forbidden_ids(d, SAFE)), d.hex()
            kinds[kind] += 1
    assert min(kinds.values()) > 100, kinds  # each kind was met


def test_compiled_cases_are_what_they_say_and_never_unsafe() -> None:
    sched = Scheduler(9, SAFE, Knowledge())
    for i in range(5000):
        c = sched.case(i)
        assert isinstance(c, Case)
        kind, answered = survey(c.data)
        assert (c.expect, c.answered) == (CLOSE if c.half_close else kind, tuple(answered)), (i, c)
        assert not forbidden_ids(c.data, SAFE), (i, c)
        assert c.size == len(c.data)
        assert pickle.loads(pickle.dumps(c)) == c  # how the prefetch child hands them over
        assert Case.from_json(c.to_json()).data == c.data  # how the corpus and the findings keep them


def test_the_compiled_stream_draws_every_origin_and_telegram() -> None:
    """The same generators and mutators at the same weights: every origin the Python stream draws in 20,000 cases
    (bar the rarest, mut.flood and a few XML attacks), every request telegram, and the hostile values."""
    compiled = Scheduler(1, MOTION, Knowledge())
    python = Scheduler(1, MOTION, Knowledge(), compiled=False)
    ours = [compiled.case(i) for i in range(20_000)]
    theirs = collections.Counter(python.case(i).origin for i in range(20_000))
    counts = collections.Counter(c.origin for c in ours)
    for origin, n in theirs.items():
        if n >= 30:  # within four standard deviations of a count's draw, and 10 %
            assert abs(counts[origin] - n) <= 4 * n**0.5 + 0.1 * n, (origin, n, counts[origin])
    assert sum(n for o, n in counts.items() if o.startswith("xml.")) >= 100  # documents stay at their weight
    assert {c.telegram for c in ours if c.origin == "gen.hostile"} == {t.name for t in generate.request_defs(MOTION)}
    notes = " ".join(c.note for c in ours if c.origin == "gen.hostile")
    for needle in ("count=-1", "count=-2147483648", "length=4294967295", "trailing bytes", "data cut"):
        assert needle in notes, needle


def test_what_was_learnt_reaches_the_compiled_draws() -> None:
    kb = Knowledge(param_keys=["fuzz.learnt_key"], stations=["learnt_station"], pose=(123_456, -654_321, 7))
    sched = Scheduler(3, MOTION, kb)
    cases = [sched.case(i) for i in range(20_000)]
    data = [c.data for c in cases]
    assert any(b"fuzz.learnt_key" in d for d in data)
    assert any(b"learnt_station" in d for d in data)
    near = (123_456 - 2000).to_bytes(4, "big", signed=True)[:2]  # the high bytes of a point near the pose
    paths = [c.data for c in cases if c.telegram == "CMD_MOVE_PATH" and c.origin == "gen.boundary"]
    assert any(near in d for d in paths)


def test_corpus_inputs_are_mutated_with_their_tags() -> None:
    """Inputs of the corpus (or imported from another worker, parallel_worker) are mutation seeds: Python draws
    those cases, and they keep the input's tags."""
    seed = Case((encode(REQUESTS.CMD_MOVE_REL(x=1, y=2, angle=3)),), "corpus", "CMD_MOVE_REL", tags=("from:1",))
    sched = Scheduler(4, MOTION, Knowledge(), pool=[seed])
    tagged = [c for c in (sched.case(i) for i in range(3000)) if c.tags == ("from:1",)]
    assert len(tagged) > 100
    assert {c.origin for c in tagged} >= {"mut.bit_flip", "mut.length_lie"}
