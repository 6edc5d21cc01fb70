"""Smoke test of the benchmark harness, and the fairness of the codec benchmark's baselines.

No timing is asserted: ``--quick`` figures mean nothing. What must hold: the runner writes every row of the
codec benchmark with positive figures and the machine's description, and the hand-written and construct
codecs decode the same frames to the same values as ``pltf.spec.codec`` (and encode them to the same bytes).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings

from benchmarks import construct_defs as cs
from benchmarks import handwritten as hw
from benchmarks.bench_codec import (
    CONSTRUCT,
    CONSTRUCT_COMPILED,
    HANDWRITTEN,
    OURS,
    Case,
    cases,
    small_telegram,
    stream_chunks,
)
from benchmarks.harness import ROW_KEYS
from pltf.spec import errors
from pltf.spec.codec import REPLIES, REQUESTS, TelegramDecoder, decode_frame, encode
from pltf.spec.strategies import telegram_strategy
from pltf.spec.telegram import Telegram, plain
from tests.benchrun import quick

ROOT = Path(__file__).resolve().parents[1]
SUBJECTS = [OURS, HANDWRITTEN, CONSTRUCT, CONSTRUCT_COMPILED]
BENCHMARKS = {
    "codec.stream_decode": ["stream_decode_rate"],
    "codec.move_vel": ["decode_rate", "encode_rate"],
    "codec.move_path": ["decode_rate", "encode_rate"],
    "codec.status": ["decode_rate", "encode_rate"],
}
TARGET_ROWS = {
    ("codec.stream_decode", OURS, "stream_decode_rate"),
    ("codec.move_vel", OURS, "decode_rate"),
    ("codec.status", OURS, "decode_rate"),
    ("codec.status", CONSTRUCT, "decode_rate"),
}


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return quick("codec", tmp_path_factory.mktemp("bench") / "bench.json", timeout=240)


def test_report_has_machine_info(report: dict[str, Any]) -> None:
    machine = report["machine"]
    assert machine["python_version"].startswith(f"{sys.version_info.major}.{sys.version_info.minor}")
    assert machine["cpu_count"] >= 1
    assert machine["platform"]
    assert report["config"]["quick"] is True
    assert report["config"]["statistic"] == "median"
    assert {b["name"] for b in report["benchmarks"]} == set(BENCHMARKS)


def test_report_has_every_row_with_positive_values(report: dict[str, Any]) -> None:
    rows = report["rows"]
    for row in rows:
        assert tuple(row) == ROW_KEYS
    got = {(r["benchmark"], r["subject"], r["metric"]) for r in rows}
    wanted = {(b, s, m) for b, metrics in BENCHMARKS.items() for m in metrics for s in SUBJECTS}
    assert got == wanted
    assert len(rows) == len(wanted)
    for r in rows:
        assert r["value"] > 0, r
        assert r["unit"] == "telegrams/s"
        if r["subject"] == HANDWRITTEN:
            assert r["baseline_subject"] is None and r["ratio"] is None
        else:
            assert r["baseline_subject"] == (HANDWRITTEN if r["subject"] == OURS else OURS)
            assert r["baseline_value"] > 0 and r["ratio"] > 0
        if (r["benchmark"], r["subject"], r["metric"]) in TARGET_ROWS:
            assert isinstance(r["target"], str) and isinstance(r["met"], bool), r
        else:
            assert r["target"] is None and r["met"] is None, r


def test_only_rejects_an_unknown_benchmark(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks", "--quick", "--only", "codec.nope", "--json", str(tmp_path / "x.json")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert proc.returncode != 0
    assert not (tmp_path / "x.json").exists()


# ---------------------------------------------------------------------------------------------- fairness


def _assert_same(frame: bytes, direction: str, case: Case) -> None:
    ours = decode_frame(frame, direction)  # type: ignore[arg-type]
    hand = case.hw_decode(frame)
    assert hand._fields == ours._fields
    assert tuple(hand) == tuple(ours)
    assert plain(hand) == ours.as_dict()  # same field names inside the groups too
    assert cs.plain(case.cs_frame.parse(frame)) == ours.as_dict()
    assert cs.plain(case.cs_compiled.parse(frame)) == ours.as_dict()
    assert case.hw_encode(hand) == frame
    assert case.cs_frame.build(ours.as_dict()) == frame


@pytest.mark.parametrize("key", ["move_vel", "move_path", "status"])
def test_baselines_decode_the_benchmark_frames_to_our_values(key: str) -> None:
    case = cases()[key]
    case.check()
    _assert_same(case.frame, case.direction, case)


def _case_for(cls: type[Telegram]) -> Case:
    return {c.telegram.NAME: c for c in cases().values()}[cls.NAME]


@pytest.mark.parametrize(
    "cls", [REQUESTS.CMD_MOVE_VEL, REQUESTS.CMD_MOVE_PATH, REPLIES.CMD_GET_STATUS], ids=lambda c: c.NAME
)
def test_baselines_agree_on_random_telegrams(cls: type[Telegram]) -> None:
    case = _case_for(cls)

    @settings(max_examples=60, deadline=None)
    @given(t=telegram_strategy(cls, max_items=20))
    def check(t: Telegram) -> None:
        _assert_same(encode(t), cls.DIRECTION, case)

    check()


def test_stream_decoders_agree() -> None:
    chunks = stream_chunks(frames=500, chunk=4096)
    ours = TelegramDecoder("request")
    hand = hw.StreamDecoder(hw.REQUEST_DECODERS)
    cons = cs.StreamDecoder(cs.MOVE_VEL_FRAME)
    got: dict[str, list[Any]] = {"ours": [], "hand": [], "cons": []}
    for chunk in chunks:
        for name, dec in (("ours", ours), ("hand", hand), ("cons", cons)):
            dec.receive_data(chunk)
            got[name].extend(dec)
    assert len(got["ours"]) == 500
    assert [tuple(t) for t in got["hand"]] == [tuple(t) for t in got["ours"]]
    assert [cs.plain(t) for t in got["cons"]] == [t.as_dict() for t in got["ours"]]


def test_handwritten_stream_decoder_survives_any_split() -> None:
    wire = encode(small_telegram()) * 3 + encode(REQUESTS.CMD_MOVE_PATH(frames=((1, 2, 3), (4, 5, 6))))
    hand = hw.StreamDecoder(hw.REQUEST_DECODERS)
    out = []
    for i in range(len(wire)):
        hand.receive_data(wire[i : i + 1])
        out.extend(hand)
    assert [tuple(t) for t in out] == [tuple(small_telegram())] * 3 + [(((1, 2, 3), (4, 5, 6)),)]


@pytest.mark.parametrize(
    "frame",
    [
        b"\xff\x01\xfe\x03" + encode(small_telegram())[4:],  # bad header
        encode(small_telegram())[:-1],  # truncated
        encode(small_telegram()) + b"\x00",  # trailing byte
    ],
)
def test_handwritten_decoder_rejects_bad_frames(frame: bytes) -> None:
    with pytest.raises(hw.DecodeError):
        hw.decode_move_vel_frame(frame)


def test_handwritten_status_checks_enums_like_ours() -> None:
    good = cases()["status"].telegram
    raw = bytearray(encode(good))
    motion_mode = len(raw) - 323 + 290  # offset of motion_mode in the fixed tail of the reply
    assert raw[motion_mode] == good.motion_mode
    raw[motion_mode] = 9
    with pytest.raises(errors.FieldOutOfRange):
        decode_frame(bytes(raw), "reply")
    with pytest.raises(hw.DecodeError):
        hw.decode_status_frame(bytes(raw))
    with pytest.raises(hw.EncodeError):
        hw.encode_status(hw.Status._make(good.replace(motion_mode=9)))


@pytest.mark.slow
def test_cli_startup_benchmark_runs_every_subject(tmp_path: Path) -> None:
    """benchmarks/bench_cli.py: every subject exits 0 (the benchmark raises otherwise), each with both metrics."""
    rows = quick("cli", tmp_path / "cli.json", timeout=600)["rows"]
    subjects = {r["subject"] for r in rows}
    assert {"python -c pass", "pltf --help", "pltf decode", "pltf encode"} <= subjects
    assert {(s, m) for s in subjects for m in ("wall_seconds", "cpu_seconds")} == {
        (r["subject"], r["metric"]) for r in rows
    }
    assert all(r["value"] > 0 for r in rows if r["subject"].startswith(("python", "pltf")))
