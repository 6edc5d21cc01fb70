"""proxy/tap.py: live decoding of one direction. The vectors of fixtures/vectors are the oracle: every valid
frame decodes to its fields however the stream is cut; every invalid one is marked with the error the vectors
name; a bad telegram does not stop the next one from decoding; a framing error marks the rest, never guesses."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from pltf.proxy.tap import FRAME, RAW, Record, Tap
from pltf.spec.codec import TelegramDecoder, decode_frame, encode
from pltf.spec.jsonio import telegram_to_json
from tests.proxy.vectors import INVALID, VALID, stream_error

STOP = encode(decode_frame(bytes.fromhex("ff01fe02000000010e"), "request"))  # CMD_STOP, field capture


def _feed(direction: str, chunks: list[bytes]) -> list[Record]:
    tap = Tap(direction, 1, 10000)  # type: ignore[arg-type]
    out: list[Record] = []
    for i, chunk in enumerate(chunks):
        out += tap.feed(chunk, float(i))
    return out + tap.end(99.0)


def test_every_valid_vector_decodes_whole_split_and_coalesced() -> None:
    for v in VALID:
        data = bytes.fromhex(v["hex"])
        for chunks in ([data], [data[i : i + 1] for i in range(len(data))], [data * 3]):
            recs = _feed(v["direction"], chunks)
            assert len(recs) == (3 if len(chunks) == 1 and len(chunks[0]) > len(data) else 1), v["name"]
            for rec in recs:
                assert rec.kind == FRAME and rec.error is None and rec.raw == data, v["name"]
                assert rec.telegram is not None
                shape = telegram_to_json(rec.telegram)
                assert (shape["telegram"], shape["id"], shape["fields"]) == (v["telegram"], v["id"], v["fields"])


def test_every_invalid_vector_is_marked_with_its_error() -> None:
    for v in INVALID:
        data = bytes.fromhex(v["hex"])
        recs = _feed(v["direction"], [data])
        bad = [r for r in recs if r.error is not None]
        assert bad, v["name"]
        assert bad[0].error is not None and bad[0].error.split(":")[0] == stream_error(v), (v["name"], bad[0].error)
        assert b"".join(r.raw for r in recs) == data, v["name"]  # every byte accounted for, none changed
        assert all(r.telegram is None for r in bad)


def test_a_bad_telegram_does_not_stop_the_next_one() -> None:
    bad = bytes.fromhex("ff01fe02000000050f00000007")  # CMD_SET_MODE 7: out of range
    recs = _feed("request", [bad + STOP])
    assert [r.error.split(":")[0] if r.error else r.name for r in recs] == ["FieldOutOfRange", "CMD_STOP"]
    assert recs[0].raw == bad and recs[1].raw == STOP


def test_after_a_framing_error_the_rest_is_marked_raw_not_guessed() -> None:
    recs = _feed("request", [STOP + b"\xff\x01\xfe\x03\x00", b"\x00\x00\x01\x0e" + STOP, STOP])
    assert [r.kind for r in recs] == [FRAME, RAW, RAW, RAW]
    assert recs[0].name == "CMD_STOP"
    assert recs[1].error and recs[1].error.startswith("BadHeader: bad header ff01fe03")
    assert recs[2].error == recs[3].error == "OutOfSync: after BadHeader"
    assert recs[3].raw == STOP and recs[3].telegram is None  # a well-formed frame after the loss is not decoded


def test_a_frame_over_the_maximum_is_refused_before_it_is_buffered() -> None:
    tap = Tap("request", 1, 10000, max_length=100)
    (rec,) = tap.feed(b"\xff\x01\xfe\x02\x00\x00\x00\x65", 0.0)
    assert rec.error == "FrameTooLarge: frame length 101 over the maximum 100"


@given(
    st.lists(st.sampled_from([v for v in VALID if v["direction"] == "request"]), min_size=1, max_size=6),
    st.lists(st.integers(1, 400), max_size=20),
)
def test_the_tap_agrees_with_the_codecs_stream_decoder(vectors: list[dict[str, str]], cuts: list[int]) -> None:
    stream = b"".join(bytes.fromhex(v["hex"]) for v in vectors)
    chunks, pos = [], 0
    for c in cuts:
        chunks.append(stream[pos : pos + c])
        pos += c
    chunks.append(stream[pos:])
    dec = TelegramDecoder("request")
    dec.receive_data(stream)
    assert [r.telegram for r in _feed("request", chunks)] == list(dec)
