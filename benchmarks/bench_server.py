"""Reference server round trips: CMD_GET_POSITION on one connection, against a bare asyncio echo server.

Set-up (issue "Reference server", benchmark): the reference server runs as its own process
(``python -m pltf.reference_server``, time scale 1, so the 50 Hz control loop runs in real time) while a second
process polls CMD_GET_STATUS at 50 Hz on the other port. The client in this process sends one
CMD_GET_POSITION at a time and waits for the reply. The baseline, in the same run, is a bare asyncio
streams server (also its own process) that answers every frame with a frame of the GET_POSITION reply's
size: the floor of this stack (Python, asyncio streams, loopback TCP).

Targets: >= 50% of the echo server's round-trip rate (time ratio <= 2), p99 latency <= 2 ms.

The helper processes run ``benchmarks.bench_server.main(["--echo"])`` and ``main(["--poll", PORT])``.
"""

from __future__ import annotations

import argparse
import asyncio
import re
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from benchmarks.harness import Config, Row, Target, benchmark, make_row, rate_rows
from pltf.spec.codec import REPLIES, REQUESTS, TelegramDecoder, decode_frame, encode

ROOT = Path(__file__).resolve().parents[1]
SERVER = "reference_server"
ECHO = "asyncio echo"
RATE_RATIO_TARGET = 2.0  # time ratio: >= 50% of the echo server's rate
P99_TARGET_MS = 2.0
POLL_HZ = 50.0
REQUEST = encode(REQUESTS.CMD_GET_POSITION())
_POSITION: Any = REPLIES.CMD_GET_POSITION  # built from the spec at import: its fields are invisible to mypy
REPLY_SIZE = len(encode(_POSITION(x=0, y=0, angle=0.0, vel_trans=0.0, vel_rot=0.0)))
STARTED = re.compile(r"server started at port (\d+)")


# ---------------------------------------------------------------------------------------------- helper processes


async def _echo_main() -> None:
    reply = b"\x00" * REPLY_SIZE

    async def client(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        buf = b""
        while data := await reader.read(65536):
            buf += data
            frames = 0
            while len(buf) >= 8 and len(buf) >= 8 + int.from_bytes(buf[4:8], "big"):
                buf = buf[8 + int.from_bytes(buf[4:8], "big") :]
                frames += 1
            if frames:
                writer.write(reply * frames)
                await writer.drain()
        writer.close()

    server = await asyncio.start_server(client, "127.0.0.1", 0)
    print(f"server started at port {server.sockets[0].getsockname()[1]}", flush=True)
    await server.serve_forever()


def _poll(port: int, hz: float) -> None:
    """Send CMD_GET_STATUS ``hz`` times a second and read the replies, until the server goes away."""
    sock = socket.create_connection(("127.0.0.1", port))
    decoder = TelegramDecoder("reply")
    request = encode(REQUESTS.CMD_GET_STATUS())
    next_at = time.monotonic()
    try:
        while True:
            sock.sendall(request)
            while decoder.next_telegram() is None:
                data = sock.recv(65536)
                if not data:
                    return
                decoder.receive_data(data)
            next_at += 1.0 / hz
            time.sleep(max(0.0, next_at - time.monotonic()))
    except OSError:
        return


# ---------------------------------------------------------------------------------------------- measurement


@contextmanager
def _process(args: list[str], log: Path, ports: int) -> Iterator[list[int]]:
    with log.open("wb") as out:
        proc = subprocess.Popen([sys.executable, *args], cwd=ROOT, stdout=out, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + 30
        while len(found := STARTED.findall(log.read_text(errors="replace"))) < ports:
            if proc.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"{args} did not start:\n{log.read_text(errors='replace')}")
            time.sleep(0.02)
        yield [int(p) for p in found]
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _round_trips(port: int, n: int) -> list[float]:
    """Seconds of each of ``n`` sequential request/reply round trips on one connection."""
    with socket.create_connection(("127.0.0.1", port)) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        buf = bytearray(REPLY_SIZE)
        view = memoryview(buf)
        times = []
        clock = time.perf_counter
        for _ in range(n):
            t0 = clock()
            sock.sendall(REQUEST)
            got = 0
            while got < REPLY_SIZE:
                k = sock.recv_into(view[got:])
                if not k:
                    raise ConnectionError("server closed the connection")
                got += k
            times.append(clock() - t0)
        return times


def _percentile(times: list[float], q: float) -> float:
    ordered = sorted(times)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def _helper(*args: str) -> list[str]:
    return ["-c", f"import sys; from benchmarks.bench_server import main; sys.exit(main({list(args)!r}))"]


@benchmark()
def get_position(config: Config) -> list[Row]:
    """GET_POSITION round trips/s and p50/p99 latency (simulation running, other port polling GET_STATUS)."""
    n = 200 if config.quick else 5000
    samples: dict[str, list[list[float]]] = {SERVER: [], ECHO: []}
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        server_args = [
            "-m",
            "pltf.reference_server",
            "--ports",
            "0,0",
            "--data-dir",
            str(tmp / "data"),
            "--time-scale",
            "1",
        ]
        with (
            _process(server_args, tmp / "server.log", 2) as ports,
            _process(_helper("--echo"), tmp / "echo.log", 1) as (echo_port,),
            _process(_helper("--poll", str(ports[1])), tmp / "poll.log", 0),
        ):
            # check once that the server's reply really is a GET_POSITION of the measured size
            with socket.create_connection(("127.0.0.1", ports[0])) as sock:
                sock.sendall(REQUEST)
                data = b""
                while len(data) < REPLY_SIZE:
                    data += sock.recv(REPLY_SIZE - len(data))
                assert decode_frame(data, "reply").NAME == "CMD_GET_POSITION"
            _round_trips(ports[0], n // 10)  # warm-up
            _round_trips(echo_port, n // 10)
            for _ in range(config.repeats):  # interleaved repeats
                samples[SERVER].append(_round_trips(ports[0], n))
                samples[ECHO].append(_round_trips(echo_port, n))
    bench = "server.get_position"
    rates = {s: statistics.median(len(t) / sum(t) for t in runs) for s, runs in samples.items()}
    rows = rate_rows(
        bench,
        "round_trip_rate",
        "1/s",
        rates,
        baselines={SERVER: ECHO},
        targets={SERVER: Target("ratio", "<=", RATE_RATIO_TARGET)},
    )
    for metric, q in (("latency_p50", 0.50), ("latency_p99", 0.99)):
        value = {s: statistics.median(_percentile(t, q) * 1000.0 for t in runs) for s, runs in samples.items()}
        target = Target("value", "<=", P99_TARGET_MS) if metric == "latency_p99" else None
        rows.append(
            make_row(
                bench,
                SERVER,
                metric,
                value[SERVER],
                "ms",
                higher_is_better=False,
                baseline_subject=ECHO,
                baseline_value=value[ECHO],
                target=target,
            )
        )
        rows.append(make_row(bench, ECHO, metric, value[ECHO], "ms", higher_is_better=False))
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="bench_server", description="helper processes of the server benchmark")
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--echo", action="store_true", help="run the baseline echo server (prints its port)")
    group.add_argument("--poll", type=int, metavar="PORT", help="poll CMD_GET_STATUS at 50 Hz on PORT")
    args = parser.parse_args(argv)
    if args.echo:
        asyncio.run(_echo_main())
    else:
        _poll(args.poll, POLL_HZ)
    return 0
