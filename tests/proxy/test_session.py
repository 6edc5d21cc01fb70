"""proxy/session.py: the session file written and read back; a file that is not one is named in one line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pltf.proxy.session import Route, SessionError, SessionWriter, read_session, record_to_json
from pltf.proxy.tap import CLOSE, OPEN, Record, Tap

SET_MODE = bytes.fromhex("ff01fe02000000050f00000003")
BAD = bytes.fromhex("ff01fe02000000050f00000007")


def _records() -> list[Record]:
    tap = Tap("request", 1, 10000)
    return [
        Record(1.0, 1, 10000, OPEN, detail="client 127.0.0.1:5000"),
        *tap.feed(SET_MODE + BAD, 1.5),
        *tap.feed(b"\x00junk", 1.6),
        Record(2.0, 1, 10000, CLOSE, detail="by client (FIN)"),
    ]


def _write(path: Path, records: list[Record]) -> None:
    w = SessionWriter(path)
    w.start([Route("127.0.0.1:20000", "10.0.0.5:10000"), Route("127.0.0.1:20002", "10.0.0.5:10002")], 0.5)
    for r in records:
        w.write(r)
    w.close()


def test_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "s.jsonl"
    records = _records()
    _write(path, records)
    s = read_session(path)
    assert s.started == 0.5 and s.ports == [10000, 10002]
    assert s.records == tuple(records)
    lines = [json.loads(x) for x in path.read_text().splitlines()]
    assert lines[2] == {
        "time": 1.5,
        "conn": 1,
        "port": 10000,
        "kind": "frame",
        "direction": "request",
        "hex": SET_MODE.hex(),
        "telegram": {"telegram": "CMD_SET_MODE", "id": 15, "fields": {"mode": 3}, "names": {"mode": "MODE_MOTION_VEL"}},
    }
    assert lines[3]["error"].startswith("FieldOutOfRange: ") and lines[3]["telegram"] is None
    assert lines[4]["kind"] == "raw" and lines[4]["error"].startswith("BadHeader")


def test_hex_is_the_truth(tmp_path: Path) -> None:
    path = tmp_path / "s.jsonl"
    _write(path, _records())
    lines = path.read_text().splitlines()
    obj = json.loads(lines[2])
    obj["telegram"] = {"telegram": "CMD_STOP"}  # edited by hand: ignored
    lines[2] = json.dumps(obj)
    path.write_text("\n".join(lines) + "\n")
    assert read_session(path).records[1].telegram == record_to_json_telegram(SET_MODE)


def record_to_json_telegram(raw: bytes) -> object:
    return Tap("request", 1, 1).feed(raw, 0.0)[0].telegram


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "empty"),
        ("{}\n", "not a pltf-session file"),
        ('{"format": "pltf-session", "version": 9, "routes": []}\n', "version 9"),
        ('{"format": "pltf-session", "version": 1, "routes": []}\nnot json\n', ":2: "),
        ('{"format": "pltf-session", "version": 1, "routes": []}\n{"kind": "frame"}\n', ":2: missing 'time'"),
        (
            '{"format": "pltf-session", "version": 1, "routes": []}\n'
            '{"time": 1, "conn": 1, "port": 1, "kind": "frame", "direction": "request",'
            ' "hex": "ff01fe02000000050f00000007"}\n',
            ":2: a frame without an error mark does not decode",
        ),
        ('{"format": "pltf-session", "version": 1, "routes": [{"listen": "a"}]}\n', ":1: the header's routes"),
    ],
)
def test_not_a_session_is_one_line(tmp_path: Path, content: str, message: str) -> None:
    path = tmp_path / "s.jsonl"
    path.write_text(content)
    with pytest.raises(SessionError, match=message) as info:
        read_session(path)
    assert "\n" not in str(info.value)


def test_a_missing_file_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(SessionError, match="No such file"):
        read_session(tmp_path / "nope.jsonl")


def test_events_keep_their_detail() -> None:
    rec = Record(3.0, 2, 10002, CLOSE, detail="by target (FIN)")
    assert record_to_json(rec) == {"time": 3.0, "conn": 2, "port": 10002, "kind": "close", "detail": "by target (FIN)"}


def test_a_repeated_frame_is_written_as_json_dumps_writes_it(tmp_path: Path) -> None:
    """The JSON of a short frame is kept and reused: every line is still exactly ``json.dumps(record_to_json)``."""
    tap = Tap("request", 3, 10002)
    records = [*tap.feed(SET_MODE + BAD, 1.25), *tap.feed(SET_MODE + BAD + b"\x00junk", 1_764_000_000.1234567)]
    records.append(Record(1_764_000_001.0, 3, 10002, CLOSE, detail="by target (FIN)"))
    path = tmp_path / "s.jsonl"
    w = SessionWriter(path)
    for r in records:
        w.write(r)
    w.close()
    assert path.read_text().splitlines() == [json.dumps(record_to_json(r)) for r in records]
    assert len({line.split('"hex"')[1] for line in path.read_text().splitlines()[:4]}) == 2  # the same frames twice
