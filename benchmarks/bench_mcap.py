"""``pltf export --mcap`` of a one-hour recording (issue 35): wall time (goal <= 10 s) and the file's size.

The recording is made here, with the codec: an application polling CMD_GET_STATUS at 20 Hz on the second port
for an hour (72,000 requests and 72,000 replies), the platform driving a circle in a 20 x 12 m room, each reply
with its 541-point scan (guide 6.4, as the reference server's scanner gives), written with the proxy's own
SessionWriter. ``--quick``: one minute.

Rows: ``pltf export --compression zstd|lz4|none`` (a subprocess each, as a user runs it, the ``mcap`` library's
writer), wall and CPU seconds, beside the baseline: reading the session alone (``read_records``: every line parsed
and decoded again from its hex, what the export read it with before issue 35's speed-up, and what ``pltf replay``
reads it with). Then reading it as the export reads it now (``read_entries``: the telegram
JSON skipped, a status's scan as numpy columns); and a floor no reader of this format goes below: the file's
lines read and each ``hex`` found and un-hexed, nothing decoded. Each MCAP file's size beside the session file's.
One run of each. On a machine shared with others the CPU seconds are the figure that compares (the wall time is
the CPU time stretched by the load).
"""

from __future__ import annotations

import io
import math
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path

from benchmarks.harness import Config, Row, Target, benchmark, make_row
from pltf.conformance_tests.readings import canonical
from pltf.proxy.mcap_export import read_records
from pltf.proxy.mcap_read import read_entries
from pltf.proxy.session import Route, SessionWriter
from pltf.proxy.tap import OPEN, Record, Tap
from pltf.spec.codec import REQUESTS, encode

HZ = 20
HOUR_S = 3600.0
TARGET_S = 10.0
ROOT = Path(__file__).resolve().parents[1]
ROOM = (20000.0, 12000.0)  # mm
SCAN = [math.radians(-135 + 0.5 * i) for i in range(541)]  # the scanner's bearings (fake_hardware)
T0 = 1_795_000_000.0
LAP = 60 * HZ  # a lap of the circle a minute
REPLY_AFTER = 0.002  # s
COMPRESSIONS = ("lz4", "zstd", "none")  # pltf export --compression; the first is the default
READ = "reading the session alone (read_records)"
ENTRIES, FLOOR = "reading it as the export does (read_entries)", "the lines read and un-hexed only"


def _wall(p: float, d: float, size: float) -> float:
    """How far along a ray from ``p`` in direction ``d`` the walls at 0 and ``size`` are (inf: parallel)."""
    if d > 1e-9:
        return (size - p) / d
    if d < -1e-9:
        return -p / d
    return math.inf


def _scan(x: float, y: float, heading: float) -> list[tuple[int, int]]:
    """Points (platform frame, mm) where the scanner's rays from (x, y) meet the room's walls."""
    points = []
    for bearing in SCAN:
        a = heading + bearing
        r = min(_wall(x, math.cos(a), ROOM[0]), _wall(y, math.sin(a), ROOM[1]), 30000.0)
        points.append((round(r * math.cos(bearing)), round(r * math.sin(bearing))))
    return points


def write_recording(path: Path, seconds: float) -> int:
    """The session file of ``seconds`` of 20 Hz status polling; the number of telegrams. A lap of the circle
    takes a minute: its 1,200 replies are made with the codec and turned into the session's JSON once (by the
    proxy's SessionWriter), and the hour repeats their lines with new times."""
    status = canonical("CMD_GET_STATUS", {})
    request = encode(REQUESTS.CMD_GET_STATUS())
    req_tap, rep_tap = Tap("request", 1, 10002), Tap("reply", 1, 10002)
    lap = io.StringIO()
    writer = SessionWriter(path)
    writer._fh.close()  # the file it opened is written below, whole
    writer._fh = lap  # the lap's lines into memory
    writer.start([Route("127.0.0.1:10000", "127.0.0.1:10000"), Route("127.0.0.1:10002", "127.0.0.1:10002")], T0)
    writer.write(Record(T0, 1, 10002, OPEN, detail="client 127.0.0.1:40000"))
    for i in range(LAP):
        phase = 2 * math.pi * i / LAP
        x, y, heading = 10000 + 4000 * math.cos(phase), 6000 + 4000 * math.sin(phase), phase + math.pi / 2
        angle = round(math.degrees(heading) * 1000) % 360000
        reply = status.replace(est_x=round(x), est_y=round(y), est_angle=angle, scan=_scan(x, y, heading))
        for rec in req_tap.feed(request, 0.0) + rep_tap.feed(encode(reply), REPLY_AFTER):
            writer.write(rec)
    head, opened, *body = lap.getvalue().splitlines()
    tails = [line.split(", ", 1)[1] for line in body]  # after '{"time": T'
    ticks = int(seconds * HZ)
    with path.open("w", encoding="ascii") as fh:
        fh.write(f"{head}\n{opened}\n")
        for i in range(ticks):
            now = T0 + i / HZ
            req, rep = tails[2 * (i % LAP)], tails[2 * (i % LAP) + 1]
            fh.write(f'{{"time": {round(now, 6)!r}, {req}\n{{"time": {round(now + REPLY_AFTER, 6)!r}, {rep}\n')
        end = round(T0 + ticks / HZ, 6)
        fh.write(f'{{"time": {end!r}, "conn": 1, "port": 10002, "kind": "close", "detail": "by client (FIN)"}}\n')
    return 2 * ticks


def export_subject(compression: str) -> str:
    return f"pltf export --mcap --compression {compression}"


def _export(session: Path, out: Path, compression: str) -> tuple[float, float]:
    """Wall and CPU seconds of ``pltf export`` as a user runs it."""
    before, t = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
    cmd = [sys.executable, "-m", "pltf.cli.main", "export", str(session), "--mcap", str(out)]
    cmd += ["--compression", compression]
    subprocess.run(cmd, check=True, capture_output=True, cwd=ROOT)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.perf_counter() - t, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def _read(session: Path, reader: Callable[[Path], Iterable[object]] = read_records) -> tuple[float, float]:
    t, cpu = time.perf_counter(), time.process_time()
    for _ in reader(session):
        pass
    return time.perf_counter() - t, time.process_time() - cpu


def unhexed(session: Path) -> Iterator[bytes]:
    """The floor: each line of the file read (binary, 4 MiB buffered) and its ``hex`` found and un-hexed."""
    with session.open("rb", buffering=4 << 20) as fh:
        for line in fh:
            start = line.find(b'"hex": "')
            if start >= 0:
                start += 8
                yield bytes.fromhex(line[start : line.index(b'"', start)].decode("ascii"))


@benchmark()
def export_hour(config: Config) -> list[Row]:
    """pltf export --mcap of an hour of 20 Hz GET_STATUS with scans (<= 10 s), each compression beside reading
    the session."""
    seconds = 60.0 if config.quick else HOUR_S
    exports = {export_subject(c): c for c in COMPRESSIONS}
    with tempfile.TemporaryDirectory() as tmp:
        session = Path(tmp) / "hour.jsonl"
        telegrams = write_recording(session, seconds)
        times: dict[str, tuple[float, float]] = {}
        sizes: dict[str, int] = {}
        for subject, compression in exports.items():  # one run of each: an hour's export is many seconds here
            out = Path(tmp) / f"hour-{compression}.mcap"
            times[subject] = _export(session, out, compression)
            sizes[subject] = out.stat().st_size
            out.unlink()
        times[READ] = _read(session)
        times[ENTRIES] = _read(session, read_entries)
        times[FLOOR] = _read(session, unhexed)
        session_size = session.stat().st_size
    name = f"mcap.export_hour ({seconds / 60:g} min, {telegrams} telegrams)"
    target = None if config.quick else Target("value", "<=", TARGET_S)
    rows = []
    for subject in exports:
        for metric, value, base in zip(("wall_seconds", "cpu_seconds"), times[subject], times[READ], strict=True):
            rows.append(
                make_row(
                    name,
                    subject,
                    metric,
                    value,
                    "s",
                    higher_is_better=False,
                    baseline_subject=READ,
                    baseline_value=base,
                    target=target if subject == export_subject(COMPRESSIONS[0]) else None,
                )
            )
    for subject in (ENTRIES, FLOOR):
        rows.append(make_row(name, subject, "wall_seconds", times[subject][0], "s", higher_is_better=False))
        rows.append(make_row(name, subject, "cpu_seconds", times[subject][1], "s", higher_is_better=False))
    for subject in exports:
        rows.append(
            make_row(
                name,
                f"the MCAP file of {subject}",
                "size",
                sizes[subject] / 1e6,
                "MB",
                higher_is_better=False,
                baseline_subject="the session file",
                baseline_value=session_size / 1e6,
            )
        )
    return rows
