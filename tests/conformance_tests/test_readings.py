"""Strict reply decoding and the alternative readings of the errata register (conformance_tests.readings)."""

from __future__ import annotations

import dataclasses
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pltf.conformance_tests import readings
from pltf.conformance_tests.outcome import BadReply
from pltf.spec.codec import REPLIES
from pltf.spec.compiler import compile_telegram
from pltf.spec.strategies import telegram_strategy

ANSWERED = [cls for cls in REPLIES if cls.DEF.answered]


@given(st.sampled_from(ANSWERED).flatmap(lambda cls: telegram_strategy(cls, max_items=3)))
def test_a_reply_in_the_decided_layout_decodes_without_deviation(t: object) -> None:
    data = REPLIES.encode_data(t)  # type: ignore[arg-type]
    got, devs = readings.decode_reply(data, t.NAME)  # type: ignore[attr-defined]
    assert got == t and devs == []


def _alt_encode(reading: readings.Reading, t: object) -> bytes:
    tdef = t.DEF  # type: ignore[attr-defined]
    assert reading.transform is not None
    cls, _, enc = compile_telegram(dataclasses.replace(tdef, reply=reading.transform(tdef.reply)), "reply")
    plain = readings._plain(t)  # type: ignore[arg-type]
    values = []
    for f in cls.DEF.reply:
        if f.const is not None:
            continue
        v = plain.get(f.name, 0)
        if f.is_group:
            v = tuple(tuple(item.get(g.name, 0) for g in f.fields if g.const is None) for item in v)
        elif f.repeat:
            v = tuple(v)[: f.repeat]
        values.append(v)
    return enc(cls._make(values))


LAYOUT_READINGS = [r for r in readings.READINGS if r.transform is not None and r.post is None]


@pytest.mark.parametrize("reading", LAYOUT_READINGS, ids=lambda r: f"{r.erratum}-{r.telegram}")
def test_each_layout_reading_decodes_to_the_canonical_telegram_with_its_deviation(reading: readings.Reading) -> None:
    base = readings.canonical(reading.telegram, {})
    if reading.telegram == "CMD_GET_CAN_MESSAGES":
        item = readings._item_class("CMD_GET_CAN_MESSAGES", "messages")
        base = base.replace(messages=(item(1.5, 0x123, (1, 2, 3, 4, 5, 6, 7, 8)),))
    if reading.telegram == "CMD_GET_STATUS":
        base = base.replace(emergency_state=2, head_position=33, us_analog_in=(1, 2, 3, 4, 0, 0, 0, 0))
    if reading.telegram in ("CMD_GET_MAP", "CMD_GET_ROADMAP"):
        base = base.replace(xml="<map/>", name="m")
    if reading.telegram == "CMD_GET_DEBUG_DATA":
        item = readings._item_class("CMD_GET_DEBUG_DATA", "person_clusters")
        base = base.replace(person_clusters=(item(1, 2, 3),))
    got, devs = readings.decode_reply(_alt_encode(reading, base), reading.telegram)
    assert got == base
    assert [d.erratum for d in devs] == [reading.erratum]


def test_two_readings_at_once_are_found() -> None:
    base = readings.canonical("CMD_GET_STATUS", {}).replace(emergency_state=1, head_position=-5 % 256)
    tdef = base.DEF
    layout = readings._retype("head_position", "BYTE")(readings._retype("emergency_state", "BYTE")(tdef.reply))
    cls, _, enc = compile_telegram(dataclasses.replace(tdef, reply=layout), "reply")
    got, devs = readings.decode_reply(enc(cls._make(tuple(base))), "CMD_GET_STATUS")
    assert got == base and {d.erratum for d in devs} == {"E-REP-009", "E-REP-011"}


def test_trailing_fields_after_the_status_are_e_rep_002() -> None:
    base = readings.canonical("CMD_GET_STATUS", {})
    got, devs = readings.decode_reply(REPLIES.encode_data(base) + b"\x01\x02\x03", "CMD_GET_STATUS")
    assert got == base and [d.erratum for d in devs] == ["E-REP-002"]


def test_validation_gate_counted_in_ints_is_e_rep_015() -> None:
    point = readings._item_class("CMD_GET_DEBUG_DATA", "validation_gate")
    base = readings.canonical("CMD_GET_DEBUG_DATA", {}).replace(validation_gate=(point(1, 2), point(3, 4)))
    data = bytearray(REPLIES.encode_data(base))
    struct.pack_into(">i", data, 1, 4)  # the count of INTs instead of points
    got, devs = readings.decode_reply(bytes(data), "CMD_GET_DEBUG_DATA")
    assert got == base and devs[0].erratum == "E-REP-015"


def _param(key: str, value: str, data_type: int, bounds: bytes) -> bytes:
    def s(x: str) -> bytes:
        return struct.pack(">i", len(x)) + x.encode()

    return s(key) + s(value) + bytes([2, data_type]) + bounds


def test_double_bounds_of_double_parameters_are_e_rep_004() -> None:
    body = (
        bytes([39])
        + struct.pack(">i", 2)
        + _param("IpoRotVel", "0.6", 2, struct.pack(">dd", 0.05, 1.5))
        + _param("IpoTransVel", "1000", 1, struct.pack(">ii", 50, 1500))
    )
    got, devs = readings.decode_reply(body, "CMD_GET_PLTF_PARAM_VEC")
    assert [(p.key, p.minimum, p.maximum) for p in got.parameters] == [("IpoRotVel", 0, 2), ("IpoTransVel", 50, 1500)]
    assert devs[0].erratum == "E-REP-004"
    single = bytes([38]) + _param("IpoRotVel", "0.6", 2, struct.pack(">dd", 0.05, 1.5))
    got, devs = readings.decode_reply(single, "CMD_GET_PLTF_PARAM")
    assert (got.key, got.maximum) == ("IpoRotVel", 2) and devs[0].erratum == "E-REP-004"


@pytest.mark.parametrize("data", [b"\x12", b"\x12" + b"\x00" * 10, bytes([74]) + b"\x00" * 7])
def test_a_reply_no_reading_explains_is_a_bad_reply(data: bytes) -> None:
    name = "CMD_GET_STATUS" if data[0] == 18 else "CMD_GET_POSITION"
    with pytest.raises(BadReply, match="does not decode"):
        readings.decode_reply(data, name)


def test_a_reply_cut_short_is_not_explained_by_trailing_fields() -> None:
    data = REPLIES.encode_data(readings.canonical("CMD_GET_STATUS", {}))
    with pytest.raises(BadReply):
        readings.decode_reply(data[:-1], "CMD_GET_STATUS")
