"""The status memo decodes exactly what the codec decodes, however the bytes vary."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from pltf.fuzz.replies import StatusMemo, reply_decoder
from pltf.reference_server.cli import build_platform
from pltf.reference_server.status import status_frame
from pltf.reference_server.storage import Storage
from pltf.spec import errors
from pltf.spec.codec import REPLIES, encode


@pytest.fixture(scope="module")
def frames(tmp_path_factory: pytest.TempPathFactory) -> list[bytes]:
    """Status frames of a platform at 20 times, two per epoch."""
    storage = Storage(Path(tmp_path_factory.mktemp("data")))
    storage.seed_from_fixtures()
    p = build_platform(storage, 1, hardware=True)
    try:
        p.boot(0.0)
        out = []
        for k in range(1, 11):
            p.tick(k * 0.1)
            out += [status_frame(p, k * 0.1 + 0.003)[1], status_frame(p, k * 0.1 + 0.007)[1]]
        return out
    finally:
        p.close()


def test_the_memo_returns_the_codecs_telegram(frames: list[bytes]) -> None:
    memo = StatusMemo()
    for frame in frames:
        data = frame[8:]
        assert memo.decode(data) == REPLIES.decode_data(data)
    assert memo.hits >= 5  # the second status of an epoch differs in its timestamp only


def test_any_other_change_is_decoded_again(frames: list[bytes]) -> None:
    memo = StatusMemo()
    data = frames[0][8:]
    memo.decode(data)
    rng = random.Random(3)
    for _ in range(200):  # one byte changed anywhere: decoded by the codec, or refused as the codec refuses
        pos = rng.randrange(1, len(data))
        bad = bytearray(data)
        bad[pos] ^= 1 << rng.randrange(8)
        try:
            want = REPLIES.decode_data(bytes(bad))
        except errors.RemoteProtocolError as exc:
            with pytest.raises(type(exc)):
                memo.decode(bytes(bad))
        else:
            assert memo.decode(bytes(bad)) == want
        memo.decode(data)


def test_the_stream_decoder_uses_it(frames: list[bytes]) -> None:
    decoder = reply_decoder()
    camera = REPLIES.CMD_GET_CAMERA(ip="10.0.0.9", camera_id="cam")
    decoder.receive_data(b"".join(frames[:4]) + encode(camera))
    assert list(decoder) == [REPLIES.decode_data(f[8:]) for f in frames[:4]] + [camera]
