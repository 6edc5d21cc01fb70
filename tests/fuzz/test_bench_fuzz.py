"""The boofuzz baseline of benchmarks/bench_fuzz.py drives the same telegrams: every request telegram of the
spec is a boofuzz request whose unmutated rendering is a frame the strict codec decodes to that telegram."""

from __future__ import annotations

import pytest

from pltf.spec.codec import decode_frame
from pltf.spec.model import load_telegrams

bf = pytest.importorskip("boofuzz")


def test_boofuzz_requests_render_valid_frames_of_every_telegram() -> None:
    from benchmarks.bench_fuzz import boofuzz_requests

    requests = boofuzz_requests(bf)
    names = {t.name for t in load_telegrams() if t.layout_known and t.request is not None}
    names -= {"CMD_EXIT", "CMD_SHUTDOWN_HOST"}
    assert {r.name for r in requests} == names
    for r in requests:
        frame = r.render()
        telegram = None
        try:
            telegram = decode_frame(frame, "request")
        except Exception as exc:  # enum fields rendered as 0 may be out of their enum: name and id must hold
            assert frame[:4] == b"\xff\x01\xfe\x02", (r.name, exc)
            assert int.from_bytes(frame[4:8], "big") == len(frame) - 8, r.name
            continue
        assert r.name == telegram.NAME
