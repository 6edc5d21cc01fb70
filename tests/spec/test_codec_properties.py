"""Properties of the codec over strategies derived from the spec (issue 2 "What must hold").

Default tier: a few hundred examples per property. `slow` tier (make test-slow): >= 10,000 each.
"""

from __future__ import annotations

import contextlib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pltf.spec import errors
from pltf.spec.codec import REPLIES, REQUESTS, TelegramDecoder, decode_frame, encode
from pltf.spec.model import DIRECTIONS, Direction
from pltf.spec.strategies import any_telegram, telegram_strategy
from pltf.spec.telegram import Telegram

SLOW = settings(max_examples=10_000, deadline=None)
ALL = [(d, cls) for d, s in (("request", REQUESTS), ("reply", REPLIES)) for cls in s]


@pytest.mark.parametrize(("direction", "cls"), ALL, ids=[f"{d}-{c.NAME}" for d, c in ALL])
@settings(max_examples=25)
@given(data=st.data())
def test_roundtrip_every_telegram(direction: Direction, cls: type[Telegram], data: st.DataObject) -> None:
    t = data.draw(telegram_strategy(cls))
    assert decode_frame(encode(t), direction) == t


def _roundtrip(direction: Direction, t: Telegram) -> None:
    wire = encode(t)
    back = decode_frame(wire, direction)
    assert back == t
    assert encode(back) == wire


@pytest.mark.parametrize("direction", DIRECTIONS)
@given(data=st.data())
def test_roundtrip_any(direction: Direction, data: st.DataObject) -> None:
    _roundtrip(direction, data.draw(any_telegram(direction)))


def _split_decode(direction: Direction, stream: bytes, cuts: list[int]) -> list[Telegram]:
    dec = TelegramDecoder(direction)
    out: list[Telegram] = []
    last = 0
    for cut in [*sorted(cuts), len(stream)]:
        if cut > last:  # b"" would mean end of stream
            dec.receive_data(stream[last:cut])
            last = cut
        out.extend(dec)
    dec.receive_data(b"")
    out.extend(dec)
    assert dec.pending == 0
    return out


@pytest.mark.parametrize("direction", DIRECTIONS)
@given(data=st.data())
def test_any_split_decodes_identically(direction: Direction, data: st.DataObject) -> None:
    telegrams = data.draw(st.lists(any_telegram(direction, max_items=3), min_size=1, max_size=5))
    stream = b"".join(encode(t) for t in telegrams)
    cuts = data.draw(st.lists(st.integers(0, len(stream)), max_size=8))
    assert _split_decode(direction, stream, cuts) == telegrams


def test_every_single_split_point_of_a_stream() -> None:
    telegrams = [
        REQUESTS.CMD_SET_MODE(mode=3),
        REQUESTS.CMD_MOVE_PATH(frames=((1, 2, 3), (-4, 5, -6))),
        REQUESTS.CMD_SET_MAP(name="Büro", xml="<map/>"),
        REQUESTS.CMD_STOP(),
    ]
    stream = b"".join(encode(t) for t in telegrams)
    for cut in range(len(stream) + 1):
        assert _split_decode("request", stream, [cut]) == telegrams
    assert _split_decode("request", stream, list(range(len(stream)))) == telegrams  # one byte at a time


def _decode_all(direction: Direction, blob: bytes) -> None:
    dec = TelegramDecoder(direction, max_length=1 << 16)
    dec.receive_data(blob)
    dec.receive_data(b"")
    with contextlib.suppress(errors.RemoteProtocolError):
        list(dec)


@pytest.mark.parametrize("direction", DIRECTIONS)
@given(blob=st.binary(max_size=200))
def test_any_bytes_decode_or_raise_codec_error(direction: Direction, blob: bytes) -> None:
    _decode_all(direction, blob)


@pytest.mark.parametrize("direction", DIRECTIONS)
@given(data=st.data())
def test_mutated_frames_decode_or_raise_codec_error(direction: Direction, data: st.DataObject) -> None:
    wire = bytearray(encode(data.draw(any_telegram(direction, max_items=3))))
    for _ in range(data.draw(st.integers(1, 4))):
        i = data.draw(st.integers(0, len(wire) - 1))
        wire[i] = data.draw(st.integers(0, 255))
    cut = data.draw(st.integers(0, len(wire)))
    _decode_all(direction, bytes(wire[:cut]) if data.draw(st.booleans()) else bytes(wire))


# --- slow tier: the issue's >= 10,000 examples per property ------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("direction", DIRECTIONS)
@SLOW
@given(data=st.data())
def test_slow_roundtrip(direction: Direction, data: st.DataObject) -> None:
    _roundtrip(direction, data.draw(any_telegram(direction)))


@pytest.mark.slow
@pytest.mark.parametrize("direction", DIRECTIONS)
@SLOW
@given(data=st.data())
def test_slow_split(direction: Direction, data: st.DataObject) -> None:
    telegrams = data.draw(st.lists(any_telegram(direction, max_items=3), min_size=1, max_size=5))
    stream = b"".join(encode(t) for t in telegrams)
    cuts = data.draw(st.lists(st.integers(0, len(stream)), max_size=8))
    assert _split_decode(direction, stream, cuts) == telegrams


@pytest.mark.slow
@pytest.mark.parametrize("direction", DIRECTIONS)
@SLOW
@given(blob=st.binary(max_size=400))
def test_slow_any_bytes(direction: Direction, blob: bytes) -> None:
    _decode_all(direction, blob)


@pytest.mark.slow
@pytest.mark.parametrize("direction", DIRECTIONS)
@SLOW
@given(data=st.data())
def test_slow_mutations(direction: Direction, data: st.DataObject) -> None:
    test_mutated_frames_decode_or_raise_codec_error.hypothesis.inner_test(direction, data)  # type: ignore[attr-defined]
