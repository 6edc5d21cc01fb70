"""``pltf proxy`` overhead and the Wireshark dissector's speed.

``proxy.get_position``: the reference server runs as its own process (time scale 1); ``pltf proxy`` runs as
its own process in front of its second port, recording (session file and pcapng, ``--quiet``), as a user runs
it. In the same run, interleaved repeat by repeat, this process sends CMD_GET_POSITION round trips on one
connection to the server's first port (direct) and through the proxy: one request at a time (latency p50/p99,
round trips per second), and in batches of ``BATCH`` requests per write (pipelined rate).
Targets (issue 21): latency p50 through the proxy <= 1.5x direct; rate >= 50 % of direct (time ratio <= 2).
The proxy forwards with its C loop (proxy/_forward.c) when it is built; ``pltf proxy --threads`` (recording),
its Python threads, runs beside it in front of the same port, so the two cores are compared in one run.
Beside them, in the same loop, the floor of a user-space forwarder (benchmarks/forwarders/): the design of the
proxy's forwarding core and nothing else, in C (``forward.c``, built here with ``cc -O2 -pthread``; without a C
compiler its rows are left out and the reason printed) and in Python (``forward.py``), each its own process in front
of the server's second port, as ``pltf proxy`` (recording) is: latency p50 and one-at-a-time rate, no target.

``proxy.tshark``: a capture of one million telegrams (500,000 GET_POSITION requests and their replies, one TCP
segment each, written with harness/pcapng.py) read by ``tshark`` with the generated dissector (proxy/pltf.lua) and,
as the baseline, by ``tshark`` without it (TCP only), output to /dev/null. No target: the issue asks how long.
"""

from __future__ import annotations

import re
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

from benchmarks.harness import Config, Row, Target, benchmark, make_row
from pltf.harness.pcapng import TcpFlow, enhanced_packet, file_header
from pltf.proxy.dissector import OUTPUT as DISSECTOR
from pltf.spec.codec import REPLIES, REQUESTS, decode_frame, encode

ROOT = Path(__file__).resolve().parents[1]
DIRECT, PROXIED, FORWARDING = "direct", "pltf proxy (recording)", "pltf proxy --quiet (forwarding only)"
THREADED = "pltf proxy --threads (recording, Python threads)"
C_FLOOR, PY_FLOOR = "C forwarder, two blocking threads", "Python forwarder, two blocking threads"
FORWARDERS = ROOT / "benchmarks" / "forwarders"
TSHARK_PLAIN, TSHARK_PLTF = "tshark (TCP only)", "tshark + pltf.lua"
FLOOR_METRICS = ("latency_p50", "round_trip_rate")  # the floors run one request at a time only
LATENCY_TARGET = 1.5  # time ratio at p50
RATE_TARGET = 2.0  # time ratio: >= 50 % of the direct rate
BATCH = 100
REQUEST = encode(REQUESTS.CMD_GET_POSITION())
_POSITION: Any = REPLIES.CMD_GET_POSITION
REPLY = encode(_POSITION(x=2000, y=10000, angle=0.0, vel_trans=0.0, vel_rot=0.0))
STARTED = re.compile(r"server started at port (\d+)")
LISTENING = re.compile(r"proxy listening at [\d.]+:(\d+)")


# ---------------------------------------------------------------------------------------------- processes


@contextmanager
def _server(tmp: Path) -> Iterator[list[int]]:
    log = tmp / "server.log"
    cmd = [
        sys.executable,
        "-m",
        "pltf.reference_server",
        "--ports",
        "0,0",
        "--data-dir",
        str(tmp / "data"),
        "--time-scale",
        "1",
    ]
    with log.open("wb") as out:
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + 60
        while len(found := STARTED.findall(log.read_text(errors="replace"))) < 2:
            if proc.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"the reference server did not start:\n{log.read_text(errors='replace')}")
            time.sleep(0.05)
        yield [int(p) for p in found]
    finally:
        proc.terminate()
        proc.wait(10)


@contextmanager
def _proxy(
    target_port: int, tmp: Path, record: str | None = "session.jsonl", extra: tuple[str, ...] = ()
) -> Iterator[int]:
    """``pltf proxy`` in front of ``target_port``, recording into ``tmp / record`` (None: no files); its listening
    port. Stopped with SIGINT (it writes its files)."""
    cmd = [
        sys.executable,
        "-m",
        "pltf.cli.main",
        "proxy",
        "--listen",
        "127.0.0.1:0",
        "--target",
        f"127.0.0.1:{target_port}",
        "--quiet",
        *extra,
    ] + (["--record", str(tmp / record)] if record is not None else [])
    with listening(cmd, stop_signal=2) as port:
        yield port


@contextmanager
def listening(cmd: list[str], stop_signal: int) -> Iterator[int]:
    """Run ``cmd``, a forwarder that prints ``proxy listening at HOST:PORT`` first; its port."""
    with subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True) as proc:
        try:
            assert proc.stdout is not None
            match = LISTENING.search(proc.stdout.readline())
            if match is None:
                raise RuntimeError(f"{cmd[0]} did not start")
            yield int(match.group(1))
        finally:
            proc.send_signal(stop_signal)
            proc.wait(600)  # pltf proxy's recorder process writes what it was handed before it ends


def build_c_forwarder(tmp: Path) -> Path | str:
    """benchmarks/forwarders/forward.c built with ``cc -O2 -pthread`` in ``tmp``: the program, or why not."""
    cc = shutil.which("cc")
    if cc is None:
        return "no C compiler (cc) on PATH"
    exe = tmp / "forward"
    cmd = [cc, "-O2", "-pthread", "-o", str(exe), str(FORWARDERS / "forward.c")]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        return f"`{' '.join(cmd)}` failed: {(proc.stderr.strip().splitlines() or ['no message'])[-1]}"
    return exe


def forwarder_commands(tmp: Path, target_port: int) -> dict[str, list[str]]:
    """The baseline forwarders' command lines, in front of ``target_port``; a C forwarder that cannot be built is
    left out, the reason printed."""
    commands = {PY_FLOOR: [sys.executable, str(FORWARDERS / "forward.py"), str(target_port)]}
    built = build_c_forwarder(tmp)
    if isinstance(built, str):
        print(f"  {C_FLOOR}: left out, {built}", file=sys.stderr)
        return commands
    return {C_FLOOR: [str(built), str(target_port)]} | commands


@contextmanager
def _floors(target_port: int, tmp: Path) -> Iterator[dict[str, int]]:
    """The baseline forwarders running in front of ``target_port``: subject -> listening port."""
    with ExitStack() as stack:
        yield {
            subject: stack.enter_context(listening(cmd, stop_signal=15))
            for subject, cmd in forwarder_commands(tmp, target_port).items()
        }


def _connect(port: int) -> socket.socket:
    deadline = time.monotonic() + 10
    while True:  # the server takes one client per port: the previous one may not be gone yet
        sock = socket.create_connection(("127.0.0.1", port))
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        try:
            sock.sendall(REQUEST)
            if _read(sock, len(REPLY)):
                return sock
        except OSError:
            pass
        sock.close()
        if time.monotonic() > deadline:
            raise RuntimeError(f"no working connection to port {port}")
        time.sleep(0.05)


def _read(sock: socket.socket, n: int) -> bytes:
    got = bytearray()
    while len(got) < n:
        data = sock.recv(max(65536, n - len(got)))
        if not data:
            return b""
        got += data
    return bytes(got)


def _round_trips(port: int, n: int) -> list[float]:
    with _connect(port) as sock:
        clock, times = time.perf_counter, []
        buf = bytearray(len(REPLY))
        view = memoryview(buf)
        for _ in range(n):
            t0 = clock()
            sock.sendall(REQUEST)
            got = 0
            while got < len(REPLY):
                k = sock.recv_into(view[got:])
                if not k:
                    raise ConnectionError("closed")
                got += k
            times.append(clock() - t0)
        return times


def _pipelined(port: int, batches: int) -> float:
    """Telegram round trips per second with BATCH requests in flight."""
    with _connect(port) as sock:
        t0 = time.perf_counter()
        for _ in range(batches):
            sock.sendall(REQUEST * BATCH)
            if not _read(sock, len(REPLY) * BATCH):
                raise ConnectionError("closed")
        return batches * BATCH / (time.perf_counter() - t0)


def _pct(times: list[float], q: float) -> float:
    ordered = sorted(times)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


@benchmark()
def get_position(config: Config) -> list[Row]:
    """GET_POSITION round trips through `pltf proxy` (recording) vs direct: latency, sequential and pipelined rate."""
    n = 300 if config.quick else 5000
    batches = 5 if config.quick else 100
    runs: dict[str, list[list[float]]] = {DIRECT: [], PROXIED: [], FORWARDING: [], THREADED: []}
    piped: dict[str, list[float]] = {DIRECT: [], PROXIED: [], FORWARDING: [], THREADED: []}
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        with (
            _server(tmp) as ports,
            _proxy(ports[1], tmp) as proxy_port,
            _proxy(ports[0], tmp, None) as bare_port,
            _proxy(ports[1], tmp, "threads.jsonl", ("--threads",)) as threaded_port,
            _floors(ports[1], tmp) as floor_ports,
        ):
            with _connect(proxy_port) as sock:  # the proxy passes a real GET_POSITION reply
                sock.sendall(REQUEST)
                assert decode_frame(_read(sock, len(REPLY)), "reply").NAME == "CMD_GET_POSITION"
            # the forwarding-only proxy shares the first port with the direct connection (one client at a time)
            port_of = {DIRECT: ports[0], PROXIED: proxy_port, FORWARDING: bare_port, THREADED: threaded_port}
            port_of |= floor_ports
            runs |= {subject: [] for subject in floor_ports}
            for port in port_of.values():  # warm-up
                _round_trips(port, n // 10)
            for _ in range(config.repeats):
                for subject, port in port_of.items():
                    runs[subject].append(_round_trips(port, n))
                    if subject in piped:  # the floors: one at a time only
                        piped[subject].append(_pipelined(port, batches))
    bench = "proxy.get_position"
    p50 = {s: statistics.median(_pct(t, 0.50) * 1e3 for t in r) for s, r in runs.items()}
    p99 = {s: statistics.median(_pct(t, 0.99) * 1e3 for t in r) for s, r in runs.items()}
    seq = {s: statistics.median(len(t) / sum(t) for t in r) for s, r in runs.items()}
    pip = {s: statistics.median(r) for s, r in piped.items()}
    # metric: (values per subject, unit, higher is better, the target of pltf proxy (recording))
    metrics: dict[str, tuple[dict[str, float], str, bool, Target | None]] = {
        "latency_p50": (p50, "ms", False, Target("ratio", "<=", LATENCY_TARGET)),
        "latency_p99": (p99, "ms", False, None),
        "round_trip_rate": (seq, "1/s", True, Target("ratio", "<=", RATE_TARGET)),
        "pipelined_rate": (pip, "telegrams/s", True, Target("ratio", "<=", RATE_TARGET)),
    }
    # beside the proxy, against direct: the forwarding-only proxy, and the floors one at a time (p50 and rate)
    others = {FORWARDING: tuple(metrics), THREADED: tuple(metrics), C_FLOOR: FLOOR_METRICS, PY_FLOOR: FLOOR_METRICS}
    rows = []
    for metric, (values, unit, higher, target) in metrics.items():
        rows.append(_against_direct(bench, PROXIED, metric, values, unit, higher, target))
        rows.append(make_row(bench, DIRECT, metric, values[DIRECT], unit, higher_is_better=higher))
    for subject, names in others.items():
        if subject in p50:  # a C forwarder that could not be built did not run
            rows += [_against_direct(bench, subject, m, *metrics[m][:3]) for m in names]
    return rows


def _against_direct(
    bench: str,
    subject: str,
    metric: str,
    values: dict[str, float],
    unit: str,
    higher: bool,
    target: Target | None = None,
) -> Row:
    """The row of ``subject``'s ``metric`` with direct as its baseline."""
    return make_row(
        bench,
        subject,
        metric,
        values[subject],
        unit,
        higher_is_better=higher,
        baseline_subject=DIRECT,
        baseline_value=values[DIRECT],
        target=target,
    )


# ---------------------------------------------------------------------------------------------- tshark


def write_capture(path: Path, telegrams: int) -> None:
    """``telegrams`` GET_POSITION requests and replies, alternating, one TCP segment each, on port 10000."""
    flow = TcpFlow(50000, 10000)
    t = 1_700_000_000.0
    with path.open("wb") as out:
        out.write(file_header())
        out.write(b"".join(enhanced_packet(ts, p) for ts, p in flow.handshake(t)))
        chunk = []
        for k in range(telegrams):
            t += 0.0001
            ((ts, pkt),) = flow.data(t, k % 2 == 0, REQUEST if k % 2 == 0 else REPLY)
            chunk.append(enhanced_packet(ts, pkt))
            if len(chunk) == 10000:
                out.write(b"".join(chunk))
                chunk.clear()
        out.write(b"".join(chunk))


def _tshark(path: Path, dissector: bool) -> float:
    cmd = ["tshark", "-r", str(path)] + (["-X", f"lua_script:{DISSECTOR}"] if dissector else [])
    t0 = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - t0


@benchmark()
def tshark(config: Config) -> list[Row]:
    """tshark with the generated dissector on a one-million-telegram capture vs tshark without it."""
    if shutil.which("tshark") is None:
        raise RuntimeError("tshark is not installed: `make tshark`")
    telegrams = 10_000 if config.quick else 1_000_000
    repeats = config.repeats if config.quick else 3
    times: dict[str, list[float]] = {TSHARK_PLAIN: [], TSHARK_PLTF: []}
    with tempfile.TemporaryDirectory() as tmp_name:
        path = Path(tmp_name) / "position.pcapng"
        write_capture(path, telegrams)
        for _ in range(repeats):
            times[TSHARK_PLAIN].append(_tshark(path, dissector=False))
            times[TSHARK_PLTF].append(_tshark(path, dissector=True))
    bench = "proxy.tshark"
    secs = {s: statistics.median(t) for s, t in times.items()}
    return [
        make_row(
            bench,
            TSHARK_PLTF,
            "seconds",
            secs[TSHARK_PLTF],
            f"s for {telegrams:,} telegrams",
            higher_is_better=False,
            baseline_subject=TSHARK_PLAIN,
            baseline_value=secs[TSHARK_PLAIN],
        ),
        make_row(
            bench, TSHARK_PLAIN, "seconds", secs[TSHARK_PLAIN], f"s for {telegrams:,} telegrams", higher_is_better=False
        ),
        make_row(
            bench, TSHARK_PLTF, "telegram_rate", telegrams / secs[TSHARK_PLTF], "telegrams/s", higher_is_better=True
        ),
    ]
