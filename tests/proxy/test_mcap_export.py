"""proxy/mcap_export.py, ``pltf export --mcap`` and ``pltf proxy --mcap`` (issue 35).

An application (examples/patrol.py, and a client on the second port asking for the map, the roadmap, the
status) runs against the reference server through ``pltf proxy --record --mcap``; the session is exported with
``pltf export``. Both files are read back by two independent readers: the Python ``mcap`` library and
``@mcap/core`` (npm, tests/proxy/mcap_reader, as Foxglove reads); the protobuf scan is decoded with the protobuf
library from the descriptor set the file carries, as Foxglove decodes it. The sans-IO parts (the scan's bins, the
documents, the order of times) are checked with exact numbers below.
"""

from __future__ import annotations

import io
import json
import math
import re
import shutil
import signal
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory, timestamp_pb2
from google.protobuf.json_format import MessageToDict
from hypothesis import given, settings
from hypothesis import strategies as st
from mcap.reader import NonSeekingReader, SeekingReader

from pltf.cli.main import main as pltf
from pltf.client import PlatformClient
from pltf.conformance_tests.readings import canonical
from pltf.harness import launch
from pltf.proxy.mcap_export import (
    CHANNELS,
    PROTOBUF,
    McapSink,
    in_time_order,
    quaternion,
    read_records,
    scan_ranges,
    stamp,
    wire_line,
)
from pltf.proxy.mcap_read import read_entries
from pltf.proxy.mcap_schemas import PROTOBUF_SCHEMAS, SCHEMAS, schema_encoding
from pltf.proxy.mcap_wire import fields_text
from pltf.proxy.session import Session, SessionError, SessionWriter, read_session
from pltf.proxy.tap import CLOSE, FRAME, OPEN, RAW, Record, Tap
from pltf.proxy.view import format_fields, format_record
from pltf.spec.codec import FRAME_OVERHEAD, REPLIES, REQUESTS, encode, telegram_set
from pltf.spec.jsonio import telegram_to_json
from pltf.spec.strategies import telegram_strategy

ROOT = Path(__file__).resolve().parents[2]
READER = ROOT / "tests" / "proxy" / "mcap_reader"
LISTENING = re.compile(r"listening at [\d.]+:(\d+)")


# ------------------------------------------------------------------------------------- the recording


def _proxy(server_ports: tuple[int, int], out: Path) -> tuple[subprocess.Popen[str], list[int]]:
    cmd = [sys.executable, "-m", "pltf.cli.main", "proxy", "--listen", "127.0.0.1:0", "--quiet"]
    cmd += ["--target", f"127.0.0.1:{server_ports[0]}", "--second", f"0:{server_ports[1]}"]
    cmd += ["--record", str(out / "session.jsonl"), "--mcap", str(out / "live.mcap")]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    ports = []
    for _ in range(2):
        m = LISTENING.search(proc.stdout.readline())
        assert m is not None, proc.stderr.read() if proc.stderr else ""
        ports.append(int(m.group(1)))
    return proc, ports


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """examples/patrol.py (two stations) through ``pltf proxy`` to the reference server at time scale 10, and a
    second client on the other port; then SIGTERM: the session, its live MCAP, and ``pltf export``'s MCAP."""
    out = tmp_path_factory.mktemp("mcap")
    with launch.reference(time_scale=10.0) as server:
        proc, ports = _proxy(server.ports, out)
        try:
            with PlatformClient("127.0.0.1", ports[1], timeout=10.0) as watch:
                watch.get_map()
                watch.get_roadmap()
                patrol = [sys.executable, str(ROOT / "examples" / "patrol.py"), "--target", f"127.0.0.1:{ports[0]}"]
                patrol += ["--stations", "Corridor_01,Corridor_02", "--rounds", "1"]
                run = subprocess.run(patrol, capture_output=True, text=True, timeout=120, check=False)
                assert run.returncode == 0, (run.stdout, run.stderr)
                for _ in range(3):
                    watch.get_status()
                    watch.get_position()
            proc.send_signal(signal.SIGTERM)
            _, err = proc.communicate(timeout=30)
        finally:
            proc.kill()
    assert proc.returncode == 0 and "Traceback" not in err, err
    assert pltf(["export", str(out / "session.jsonl"), "--mcap", str(out / "export.mcap")]) == 0
    for compression in ("zstd", "none"):  # the default is lz4
        args = ["export", str(out / "session.jsonl"), "--mcap", str(out / f"export-{compression}.mcap")]
        assert pltf([*args, "--compression", compression]) == 0
    return out


EXPORTS = {"export.mcap": "lz4", "export-zstd.mcap": "zstd", "export-none.mcap": "", "live.mcap": "lz4"}  # chunks


def _telegrams(session: Session) -> list[Record]:
    return [r for r in session.records if r.kind in (FRAME, RAW)]


def _protobuf_class(schema: Any) -> Any:
    """The message class of a protobuf schema, built from the FileDescriptorSet the MCAP file carries."""
    files = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    for f in files.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


def _decode(schema: Any, channel: Any, data: bytes) -> dict[str, Any]:
    if channel.message_encoding == "json":
        return json.loads(data)  # type: ignore[no-any-return]
    assert channel.message_encoding == "protobuf" and schema.encoding == "protobuf"
    message = _protobuf_class(schema).FromString(data)
    return MessageToDict(message, preserving_proto_field_name=True, always_print_fields_with_no_presence=True)


def _python_read(path: Path) -> dict[str, Any]:
    """What the Python mcap library reads: streamed record by record, and through the summary's indexes."""
    counts: Counter[str] = Counter()
    last: dict[str, int] = {}
    monotonic = True
    schemas: dict[str, tuple[str, str, str]] = {}
    messages: dict[str, list[dict[str, Any]]] = {}
    with path.open("rb") as fh:
        for schema, channel, message in NonSeekingReader(fh, validate_crcs=True).iter_messages():
            assert schema is not None, f"{channel.topic} has no schema"
            schemas[channel.topic] = (schema.name, schema.encoding, channel.message_encoding)
            counts[channel.topic] += 1
            monotonic &= message.log_time >= last.get(channel.topic, 0)
            last[channel.topic] = message.log_time
            messages.setdefault(channel.topic, []).append(_decode(schema, channel, message.data))
    with path.open("rb") as fh:
        reader = SeekingReader(fh, validate_crcs=True)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        indexed = Counter(ch.topic for _, ch, _ in reader.iter_messages())
        topics = {cid: ch.topic for cid, ch in summary.channels.items()}
        declared = {cid: summary.schemas[ch.schema_id].name for cid, ch in summary.channels.items()}
    return {
        "counts": counts,
        "indexed": indexed,
        "monotonic": monotonic,
        "schemas": schemas,
        "declared": {topics[c]: n for c, n in declared.items()},
        "messages": messages,
        "statistics": summary.statistics,
        "channel_counts": {topics[c]: n for c, n in summary.statistics.channel_message_counts.items()},
        "chunks": summary.chunk_indexes,
        "topics": topics,
    }


@pytest.mark.parametrize("which", list(EXPORTS))
def test_the_python_mcap_library_reads_every_telegram_with_known_schemas_and_consistent_indexes(
    recorded: Path, which: str
) -> None:
    session = read_session(recorded / "session.jsonl")
    got = _python_read(recorded / which)
    assert got["declared"] == CHANNELS  # every channel, its schema declared in the summary
    for topic, (name, encoding, message_encoding) in got["schemas"].items():
        want = "protobuf" if topic in PROTOBUF else "json"
        assert (name, encoding, message_encoding) == (CHANNELS[topic], schema_encoding(name), want), topic
        assert name in SCHEMAS or name in PROTOBUF_SCHEMAS
    assert got["schemas"]["/scan"] == ("foxglove.LaserScan", "protobuf", "protobuf")
    telegrams = _telegrams(session)
    assert got["counts"]["/pltf/telegrams"] == len(telegrams) > 50
    assert got["counts"]["/pltf/wire"] == len(session.records)  # a line per telegram and per connection event
    assert {"/pose", "/tf", "/scan", "/map"} <= set(got["counts"])
    assert got["monotonic"]
    stats = got["statistics"]
    assert stats.message_count == sum(got["counts"].values())
    assert got["channel_counts"] == dict(got["counts"])
    assert got["indexed"] == got["counts"]  # the chunk and message indexes lead to every message
    assert stats.chunk_count == len(got["chunks"]) >= 1
    assert {c.compression for c in got["chunks"]} == {EXPORTS[which]}
    assert stats.message_start_time == min(c.message_start_time for c in got["chunks"])
    assert stats.message_end_time == max(c.message_end_time for c in got["chunks"])
    first, last = telegrams[0].time, telegrams[-1].time
    assert stats.message_start_time <= round(first * 1e9) and stats.message_end_time >= round(last * 1e9)


def test_the_raw_channel_holds_every_telegram_of_the_recording_in_order(recorded: Path) -> None:
    session = read_session(recorded / "session.jsonl")
    raw = _python_read(recorded / "export.mcap")["messages"]["/pltf/telegrams"]
    want = sorted(_telegrams(session), key=lambda r: r.time)
    assert [(m["conn"], m["port"], m["direction"], m["hex"]) for m in raw] == [
        (r.conn, r.port, r.direction, r.raw.hex()) for r in want
    ]
    assert {m["port"] for m in raw} == set(session.ports)  # both ports, both directions
    assert {m["direction"] for m in raw} == {"request", "reply"}


def test_the_pose_messages_are_the_get_position_replies(recorded: Path) -> None:
    session = read_session(recorded / "session.jsonl")
    replies = sorted(
        (r for r in session.records if r.telegram is not None and r.telegram.NAME == "CMD_GET_POSITION"),
        key=lambda r: r.time,
    )
    replies = [r for r in replies if r.direction == "reply"]
    poses = _python_read(recorded / "export.mcap")["messages"]["/pose"]
    assert len(poses) == len(replies) >= 3
    for pose, rec in zip(poses, replies, strict=True):
        t: Any = rec.telegram  # decoded again from the session's hex by read_session
        assert pose["timestamp"] == stamp(rec.time) and pose["frame_id"] == "map"
        assert pose["pose"]["position"] == {"x": t.x / 1000, "y": t.y / 1000, "z": 0.0}
        q = pose["pose"]["orientation"]
        assert q == {"x": 0.0, "y": 0.0, "z": math.sin(t.angle / 2), "w": math.cos(t.angle / 2)}
        assert round(pose["pose"]["position"]["x"] * 1000) == t.x and 2 * math.atan2(q["z"], q["w"]) == pytest.approx(
            t.angle
        )


def test_each_compression_carries_the_same_messages(recorded: Path) -> None:
    lz4 = _python_read(recorded / "export.mcap")["messages"]
    for which in ("export-zstd.mcap", "export-none.mcap"):
        assert _python_read(recorded / which)["messages"] == lz4, which
    sizes = [(recorded / w).stat().st_size for w in ("export-zstd.mcap", "export.mcap", "export-none.mcap")]
    assert sizes == sorted(sizes), sizes  # zstd smallest, lz4, none largest


@pytest.mark.skipif(shutil.which("node") is None, reason="node is not installed")
@pytest.mark.parametrize("which", list(EXPORTS))
def test_mcap_core_from_npm_reads_the_same(recorded: Path, which: str) -> None:
    if not (READER / "node_modules" / "@mcap" / "core").is_dir():
        pytest.fail(f"@mcap/core is not installed: make {READER.relative_to(ROOT)}/node_modules/.installed")
    proc = subprocess.run(
        ["node", str(READER / "read.mjs"), str(recorded / which)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout)
    ours = _python_read(recorded / which)
    stream, indexed = got["stream"], got["indexed"]
    assert stream["done"] and stream["monotonic"]
    assert {c["topic"]: c["schemaName"] for c in stream["channels"]} == CHANNELS
    for c in stream["channels"]:
        want = ("protobuf", "protobuf") if c["topic"] in PROTOBUF else ("jsonschema", "json")
        assert (c["schemaEncoding"], c["messageEncoding"]) == want, c
    assert stream["counts"] == dict(ours["counts"])
    # protobufjs (Foxglove's decoder) from the file's own FileDescriptorSet reads the scans the protobuf library reads
    theirs = stream["decoded"]["/scan"]
    assert len(theirs) == len(ours["messages"]["/scan"]) >= 3
    for js, py in zip(theirs, ours["messages"]["/scan"], strict=True):
        assert (js["ranges"], js["start_angle"], js["end_angle"], js["frame_id"]) == (
            py["ranges"],
            py["start_angle"],
            py["end_angle"],
            py["frame_id"],
        )
        assert js["pose"] == {"position": {"x": 0, "y": 0, "z": 0}, "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}
    assert stream["counts"]["/pltf/telegrams"] == len(_telegrams(read_session(recorded / "session.jsonl")))
    stats = indexed["statistics"]
    assert int(stats["messageCount"]) == sum(stream["counts"].values())
    assert {k: int(v) for k, v in stats["channelMessageCounts"].items()} == stream["counts"]
    assert stats["channelCount"] == len(CHANNELS) and stats["chunkCount"] == len(indexed["chunks"])
    assert {c["compression"] for c in indexed["chunks"]} == {EXPORTS[which]}
    assert indexed["counts"] == stream["counts"]  # readMessages() goes through the chunk and message indexes
    assert stats["messageStartTime"] == stream["start"] and stats["messageEndTime"] == stream["end"]


@pytest.mark.skipif(shutil.which("node") is None, reason="node is not installed")
@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_a_session_without_traffic_is_an_mcap_file_of_no_messages_both_readers_read(
    tmp_path: Path, compression: str
) -> None:
    (tmp_path / "session.jsonl").write_text('{"format": "pltf-session", "version": 1, "started": 0, "routes": []}\n')
    out = tmp_path / "empty.mcap"
    assert pltf(["export", str(tmp_path / "session.jsonl"), "--mcap", str(out), "--compression", compression]) == 0
    ours = _python_read(out)
    assert ours["counts"] == {} and ours["statistics"].message_count == 0 and ours["chunks"] == []
    assert ours["declared"] == CHANNELS
    cmd = ["node", str(READER / "read.mjs"), str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=60, check=False)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout)
    assert got["stream"]["done"] and got["stream"]["counts"] == {} and got["indexed"]["chunks"] == []
    assert int(got["indexed"]["statistics"]["messageCount"]) == 0


def test_pltf_proxy_mcap_live_has_the_counts_of_the_export_of_its_own_recording(recorded: Path) -> None:
    live, export = _python_read(recorded / "live.mcap"), _python_read(recorded / "export.mcap")
    assert live["counts"] == export["counts"]
    assert not list(recorded.glob(".*.tmp"))  # renamed into place, nothing left beside


# ------------------------------------------------------------------------------------------ bad input


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\x00\xff\x10garbage", "not a text file"),
        (b"hello\n", "session.jsonl:1"),
        (b'{"format": "pltf-session", "version": 1, "started": 0, "routes": []}\n{"kind": "frame"}\n', ":2: missing"),
    ],
)
def test_a_bad_session_file_is_one_line_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: bytes, message: str
) -> None:
    (tmp_path / "session.jsonl").write_bytes(content)
    assert pltf(["export", str(tmp_path / "session.jsonl"), "--mcap", str(tmp_path / "out.mcap")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pltf export: error: ") and message in err and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == [tmp_path / "session.jsonl"]


def test_pltf_proxy_refuses_an_unwritable_mcap_in_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = ["proxy", "--listen", "127.0.0.1:0", "--target", "127.0.0.1:1", "--mcap", str(tmp_path / "no" / "x.mcap")]
    assert pltf(args) == 2
    err = capsys.readouterr().err
    assert "cannot write the MCAP file" in err and err.count("\n") == 1, err


# ------------------------------------------------------------------------------- sans-IO, exact numbers


def _read(buf: io.BytesIO) -> dict[str, list[tuple[int, int, dict[str, Any]]]]:
    buf.seek(0)
    out: dict[str, list[tuple[int, int, dict[str, Any]]]] = {}
    for schema, channel, m in NonSeekingReader(buf).iter_messages():
        out.setdefault(channel.topic, []).append((m.log_time, m.publish_time, _decode(schema, channel, m.data)))
    return out


def test_a_record_earlier_than_its_channels_last_keeps_log_times_monotonic_and_its_publish_time() -> None:
    buf = io.BytesIO()
    sink = McapSink(buf)
    sink.write(Record(10.0, 1, 10000, OPEN, detail="client 127.0.0.1:5"))
    sink.write(Record(12.0, 2, 10000, OPEN, detail="client 127.0.0.1:6"))
    sink.write(Record(11.0, 1, 10000, CLOSE, detail="by client (FIN)"))  # written late, as the recorder does
    sink.finish()
    wire = _read(buf)["/pltf/wire"]
    assert [(log, pub) for log, pub, _ in wire] == [
        (10 * 10**9, 10 * 10**9),
        (12 * 10**9, 12 * 10**9),
        (12 * 10**9, 11 * 10**9),
    ]
    assert wire[2][2]["message"] == "#1   :10000    close by client (FIN)"
    assert wire[2][2]["timestamp"] == {"sec": 11, "nsec": 0}


def test_malformed_bytes_are_on_the_raw_channel_with_their_error_and_a_warning_line() -> None:
    records = Tap("request", 3, 10002).feed(b"\xff\x01\xfe\x03\x00\x00\x00\x01J", 5.5)
    assert [r.kind for r in records] == [RAW]
    buf = io.BytesIO()
    sink = McapSink(buf)
    sink.write(records[0])
    sink.finish()
    got = _read(buf)
    (_, _, raw), (_, _, log) = got["/pltf/telegrams"][0], got["/pltf/wire"][0]
    assert raw == {
        "timestamp": {"sec": 5, "nsec": 500000000},
        "conn": 3,
        "port": 10002,
        "direction": "request",
        "kind": "raw",
        "name": "malformed",
        "hex": "ff01fe03000000014a",
        "error": "BadHeader: bad header ff01fe03 (expected ff01fe02)",
    }
    assert log["level"] == 3 and "MALFORMED BadHeader" in log["message"]


def _scan(points: list[tuple[int, int]]) -> tuple[float, float, list[float]]:
    xy = np.array(points, dtype=np.int16)
    start, end, ranges = scan_ranges(xy[:, 0], xy[:, 1])
    return start, end, ranges.tolist()


def test_scan_points_go_into_half_degree_bins_by_bearing_with_exact_ranges() -> None:
    # 1 m ahead, 2 m at +1 degree (bin 2), nothing at +0.5 degree (bin 1), 3 m to the left (+90: bin 180)
    ahead, one_degree = (
        (1000, 0),
        (round(2000 * math.cos(math.radians(1))), round(2000 * math.sin(math.radians(1)))),
    )
    start, end, ranges = _scan([ahead, one_degree, (0, 3000)])
    assert (start, end) == (0.0, 180 * math.radians(0.5)) and len(ranges) == 181
    assert ranges[0] == 1.0 and ranges[1] == 0.0 and ranges[2] == pytest.approx(2.0, abs=1e-3) and ranges[180] == 3.0
    assert _scan([(1000, 0), (500, 0)])[2] == [0.5]  # the nearest point wins a bin
    assert _scan([(500, 0), (1000, 0), (0, -700)])[2][::180] == [0.7, 0.5]  # in any order


def _expected_bins(points: tuple[Any, ...]) -> dict[int, float]:
    """The oracle: each point's 0.5 degree bin by its bearing, the nearest point's range (m, to the mm), in plain
    Python floats from the codec's decoded points."""
    bins: dict[int, float] = {}
    for p in points:
        b, r = round(math.atan2(p.y, p.x) / math.radians(0.5)), math.hypot(p.x, p.y) / 1000
        bins[b] = min(bins.get(b, r), r)
    return {b: round(r, 3) for b, r in bins.items()}


def test_each_laser_scan_decoded_by_protobuf_holds_its_status_replys_scan_as_the_codec_decodes_it(
    recorded: Path,
) -> None:
    session = read_session(recorded / "session.jsonl")
    replies = sorted(
        (r for r in session.records if r.direction == "reply" and r.telegram and r.telegram.NAME == "CMD_GET_STATUS"),
        key=lambda r: r.time,
    )
    scans = _python_read(recorded / "export.mcap")["messages"]["/scan"]
    with_points = [r for r in replies if r.telegram.scan]  # type: ignore[union-attr]
    assert len(scans) == len(with_points) >= 3
    assert max(len(r.telegram.scan) for r in with_points) > 100  # type: ignore[union-attr]  # a real scan
    for scan, rec in zip(scans, with_points, strict=True):
        want = _expected_bins(rec.telegram.scan)  # type: ignore[union-attr]
        lo, hi = min(want), max(want)
        when = timestamp_pb2.Timestamp()
        when.FromJsonString(scan["timestamp"])
        assert {"sec": when.seconds, "nsec": when.nanos} == stamp(rec.time)
        assert scan["frame_id"] == "base_link" and scan["pose"]["orientation"] == {"x": 0, "y": 0, "z": 0, "w": 1.0}
        assert scan["start_angle"] == pytest.approx(lo * math.radians(0.5), abs=1e-12)
        assert scan["end_angle"] == pytest.approx(hi * math.radians(0.5), abs=1e-12)
        assert scan["ranges"] == [want.get(b, 0.0) for b in range(lo, hi + 1)]
        assert scan["intensities"] == []


def test_the_map_and_the_roadmap_become_scene_entities() -> None:
    office_map = (ROOT / "fixtures" / "maps" / "office.map").read_text(encoding="utf-8")
    office_rm = (ROOT / "fixtures" / "roadmaps" / "office.rm").read_text(encoding="utf-8")
    tap = Tap("reply", 1, 10000)
    records = tap.feed(encode(REPLIES.CMD_GET_MAP(xml=office_map, name="office")), 1.0)
    records += tap.feed(encode(REPLIES.CMD_GET_ROADMAP(xml=office_rm, name="office")), 2.0)
    records += tap.feed(encode(REPLIES.CMD_GET_MAP(xml="<map><oops/></map>", name="bad")), 3.0)
    buf = io.BytesIO()
    sink = McapSink(buf)
    for r in records:
        sink.write(r)
    sink.finish()
    got = _read(buf)
    (_, _, scene_map), (_, _, scene_rm) = got["/map"]
    lines = office_map.count("<line>")
    (map_entity,) = scene_map["entities"]
    assert map_entity["id"] == "map" and len(map_entity["lines"][0]["points"]) == 2 * lines
    assert map_entity["lines"][0]["points"][:2] == [{"x": 0.0, "y": 0.0, "z": 0.0}, {"x": 32.0, "y": 0.0, "z": 0.0}]
    (rm_entity,) = scene_rm["entities"]
    names = [t["text"] for t in rm_entity["texts"]]
    assert names[:2] == ["Corridor_W", "Corridor_01"] and len(names) == office_rm.count("<station ")
    assert rm_entity["texts"][1]["pose"]["position"] == {"x": 5.0, "y": 10.0, "z": 0.0}
    warning = got["/pltf/wire"][-1][2]
    assert warning["level"] == 3 and warning["message"].startswith("CMD_GET_MAP reply: the document is not shown:")


def test_a_request_makes_no_scene_message() -> None:
    (rec,) = Tap("request", 1, 10000).feed(encode(REQUESTS.CMD_GET_POSITION()), 1.0)
    buf = io.BytesIO()
    sink = McapSink(buf)
    sink.write(rec)
    sink.finish()
    assert sink.counts == {**dict.fromkeys(CHANNELS, 0), "/pltf/telegrams": 1, "/pltf/wire": 1}
    assert quaternion(0.0) == {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}


def test_the_wire_line_of_a_status_with_its_scan_is_the_views_line() -> None:
    status = canonical("CMD_GET_STATUS", {}).replace(scan=[(i, -i) for i in range(541)], est_x=12)
    (rec,) = Tap("reply", 2, 10002).feed(encode(status), 7.25)
    assert wire_line(rec) == format_record(rec, t0=7.25)[1].lstrip().split(" ", 1)[1]
    assert " scan=[541: {x=0 y=0}, {x=1 y=-1}, {x=2 y=-2}, ...] " in wire_line(rec)


ENTRY_FIELDS = ("time", "conn", "port", "kind", "direction", "raw", "error", "detail")


def _session_file(path: Path, lines: list[str], newline: str = "\n") -> Path:
    header = '{"format": "pltf-session", "version": 1, "started": 0, "routes": []}'
    path.write_text(newline.join([header, *lines]) + newline, encoding="ascii", newline="")
    return path


def test_read_entries_reads_what_read_records_reads_line_by_line(tmp_path: Path) -> None:
    """Every kind of line, the fast way (SessionWriter's frame lines) and the slow (the rest), with CRLF too."""
    status = canonical("CMD_GET_STATUS", {}).replace(scan=[(i, -i) for i in range(50)])
    recs = Tap("reply", 1, 10002).feed(encode(status), 2.0) + Tap("request", 1, 10002).feed(b"\xff\x01\xfe\x03xyz", 3.0)
    recs += Tap("reply", 2, 10000).feed(
        encode(REPLIES.CMD_GET_POSITION(x=1, y=2, angle=0.5, vel_trans=0, vel_rot=0)), 4
    )
    buf = io.StringIO()
    writer = SessionWriter(tmp_path / "unused.jsonl")
    writer.close()
    writer._fh = buf  # the lines into memory
    writer.write(Record(1.0, 1, 10002, OPEN, detail="client 127.0.0.1:5"))
    for r in recs:
        writer.write(r)
    writer.write(Record(5.0, 1, 10002, CLOSE, detail="by client (FIN)"))
    lines = buf.getvalue().splitlines()
    marked = '{"time": 6, "conn": 3, "port": 10000, "kind": "frame", "direction": "reply", "hex": "ff01fe02", '
    lines += ["", marked + '"telegram": null, "error": "Truncated: short"}']
    for newline in ("\n", "\r\n"):
        path = _session_file(tmp_path / "s.jsonl", lines, newline)
        got = [tuple(getattr(e, f) for f in ENTRY_FIELDS) for e in read_entries(path)]
        assert got == [tuple(getattr(r, f) for f in ENTRY_FIELDS) for r in read_records(path)]
        assert len(got) == 6 and got[-1][6] == "Truncated: short"


@pytest.mark.parametrize(
    "line",
    [
        '{"time": 1, "conn": 1, "port": 1, "kind": "frame", "direction": "reply", "hex": "ff01fe020000000112", '
        '"telegram": {}}',  # a CMD_GET_STATUS reply without its fields does not decode
        '{"time": 1, "conn": 1, "port": 1, "kind": "frame", "direction": "sideways", "hex": "", "telegram": {}}',
        '{"time": 1, "conn": 1, "port": 1, "kind": "frame", "direction": "reply", "hex": "zz", "telegram": {}}',
        '{"time": 1, "conn": 1, "port": 1, "kind": "frame", "direction": "reply", "hex": "ff01',  # cut short
    ],
)
def test_read_entries_refuses_a_bad_line_with_read_records_message(tmp_path: Path, line: str) -> None:
    path = _session_file(tmp_path / "s.jsonl", ["", line])
    with pytest.raises(SessionError) as want:
        list(read_records(path))
    with pytest.raises(SessionError) as got:
        list(read_entries(path))
    assert str(got.value) == str(want.value) and ":3: " in str(got.value)


EVERY_CLASS = [cls for direction in ("request", "reply") for cls in telegram_set(direction)]


@settings(max_examples=400, deadline=None)
@given(st.sampled_from(EVERY_CLASS).flatmap(lambda cls: telegram_strategy(cls, max_items=6)))
def test_the_compiled_wire_words_are_the_views_for_every_telegram(t: Any) -> None:
    decoded = telegram_set(t.DIRECTION).decode_data(encode(t)[FRAME_OVERHEAD:])  # group items as the codec makes them
    assert fields_text(decoded) == format_fields(telegram_to_json(decoded))


def test_records_are_put_in_time_order_within_the_window_and_a_session_reads_as_read_session_reads_it(
    recorded: Path,
) -> None:
    late = [Record(t, 1, 10000, OPEN) for t in (1.0, 2.0, 3.0)] + [Record(1.5, 1, 10000, CLOSE)]
    assert [r.time for r in in_time_order(late)] == [1.0, 1.5, 2.0, 3.0]
    assert [r.time for r in in_time_order([*late, Record(20.0, 2, 10000, OPEN), Record(1.2, 2, 10000, CLOSE)])] == [
        1.0,
        1.5,
        2.0,
        3.0,
        1.2,  # more than the window late (3.0 was passed on already): passed on at once
        20.0,
    ]
    assert tuple(read_records(recorded / "session.jsonl")) == read_session(recorded / "session.jsonl").records
    fields = ENTRY_FIELDS
    entries = list(read_entries(recorded / "session.jsonl"))
    records = read_session(recorded / "session.jsonl").records
    assert [tuple(getattr(e, f) for f in fields) for e in entries] == [
        tuple(getattr(r, f) for f in fields) for r in records
    ]
    for e, r in zip(entries, records, strict=True):  # whole, or the first items of each column
        if e.columns:
            assert r.telegram is not None and e.telegram is not None
            cut = {c.name: c for c in e.columns}
            assert e.telegram == r.telegram.replace(**{n: getattr(r.telegram, n)[:3] for n in cut})
            for name, c in cut.items():
                assert [tuple(item) for item in c.items.tolist()] == list(getattr(r.telegram, name))
        else:
            assert e.telegram == r.telegram
