"""values.rewrite: the doubles of GET_POSITION and GET_STATUS in each style, byte-exact; every other frame passes."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from pltf.spec.codec import REPLIES, decode_frame, encode
from pltf.zoo.frames import FrameCutter, Piece
from pltf.zoo.values import STYLES, rewrite

# CMD_GET_POSITION x=1, y=2, angle=1.2 rad, vel_trans=300 mm/s, vel_rot=-1.5 rad/s: guide 6.2, big-endian doubles
POSITION = bytes.fromhex(
    "ff01fe02 00000021 4a 00000001 00000002 3ff3333333333333 4072c00000000000 bff8000000000000".replace(" ", "")
)
VECTORS = {
    v["name"]: v
    for v in json.loads((Path(__file__).resolve().parents[2] / "fixtures" / "vectors" / "replies.json").read_text())
}
STATUS = bytes.fromhex(VECTORS["reply_status_full_541_scan_points"]["hex"])


def piece(data: bytes) -> Piece:
    [p] = FrameCutter().feed(data)
    return p


def test_the_vector_is_the_codecs_position_reply() -> None:
    assert encode(REPLIES.CMD_GET_POSITION(x=1, y=2, angle=1.2, vel_trans=300.0, vel_rot=-1.5)) == POSITION


def test_little_endian_reverses_the_bytes_of_each_double_only() -> None:
    out = rewrite(piece(POSITION), "little-endian")
    assert out[:17] == POSITION[:17] and len(out) == len(POSITION)
    for at in (17, 25, 33):
        assert out[at : at + 8] == POSITION[at : at + 8][::-1]


@pytest.mark.parametrize(("style", "check"), [("nan", math.isnan), ("inf", lambda v: v == math.inf)])
def test_nan_and_inf_fill_every_double_of_position_and_status(style: str, check: object) -> None:
    status = STATUS
    got_pos = decode_frame(rewrite(piece(POSITION), style), "reply")
    got_status = decode_frame(rewrite(piece(status), style), "reply")
    assert (got_pos.x, got_pos.y) == (1, 2)
    assert all(check(getattr(got_pos, n)) for n in ("angle", "vel_trans", "vel_rot"))  # type: ignore[operator]
    assert all(check(getattr(got_status, n)) for n in ("gps_latitude", "gps_longitude"))  # type: ignore[operator]
    assert len(rewrite(piece(status), style)) == len(status)


def test_other_frames_and_frames_that_do_not_decode_pass_unchanged() -> None:
    for name in ("reply_get_pltf_param_double", "reply_get_map", "reply_can_messages_one"):
        data = bytes.fromhex(VECTORS[name]["hex"])
        assert rewrite(piece(data), "nan") == data
    cut_short = Piece(POSITION[:8] + POSITION[8:20], True)  # header says 33 bytes, 12 came: no decode
    assert rewrite(cut_short, "inf") == cut_short.data
    assert set(STYLES) == {"little-endian", "nan", "inf"}
