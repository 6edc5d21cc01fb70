"""Fuzzing rate against the reference server: ``pltf fuzz`` versus boofuzz driving the same telegrams.

Set-up: each subject gets a fresh ``python -m pltf.reference_server`` (own process, own data dir, log level ERROR
so that neither pays for the server's per-connection INFO lines) and runs for the same wall time (10 s),
three times, interleaved; the median rate is reported.

- ``pltf fuzz``: the network campaign of ``pltf.fuzz.engine`` as ``pltf fuzz --allow-motion`` runs it (state
  preludes, batching of the cases the codec accepts, one connection per case it refuses, the GET_STATUS
  liveness probe on the other port every 4 units).
- ``pltf fuzz, probe every unit``: the same with the probe after every unit (the strictest oracle).
- ``pltf fuzz, natural mix``: the same with every drawn case over 1 MiB kept (``--big-share 1``); by default
  the scheduler keeps a quarter of them (``pltf.fuzz.schedule``: each costs the target up to 0.6 s).
- ``boofuzz``: one boofuzz request per request telegram of the spec (header and length as boofuzz
  primitives, the length computed by ``s_size`` over the data block, every field fuzzable with boofuzz's
  own value library), a ``Session`` on a TCP connection with no sleeps and no receive, the web UI off,
  results in a throw-away sqlite file: boofuzz as one would set it up for speed.

A case is one test case: one boofuzz mutation, one ``pltf fuzz`` case. Targets (issue "Protocol fuzzer"):
>= 3,000 cases/s and >= 10x boofuzz (time ratio <= 0.1).
"""

from __future__ import annotations

import contextlib
import io
import socket
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from benchmarks.harness import Config, Row, Target, benchmark, make_row
from pltf.fuzz.engine import Campaign, Options
from pltf.fuzz.launch import Launcher
from pltf.fuzz.schedule import BIG_SHARE
from pltf.spec.model import FieldDef, load_telegrams

OURS = "pltf fuzz"
OURS_STRICT = "pltf fuzz, probe every unit"
OURS_NATURAL = "pltf fuzz, natural mix (--big-share 1)"
BOOFUZZ = "boofuzz"
RATE_TARGET = 3000.0
SPEEDUP_TARGET = 10.0
LAUNCH = f"{sys.executable} -m pltf.reference_server --ports {{ports}} --data-dir {{tmpdir}} --seed 1 --log-level ERROR"


def free_ports() -> tuple[int, int]:
    socks = [socket.socket() for _ in range(2)]
    try:
        for s in socks:
            s.bind(("127.0.0.1", 0))
        a, b = (s.getsockname()[1] for s in socks)
        return a, b
    finally:
        for s in socks:
            s.close()


@contextlib.contextmanager
def reference_server() -> Iterator[tuple[int, int]]:
    a, b = free_ports()
    launcher = Launcher(LAUNCH, "127.0.0.1", a, b)
    launcher.start()
    try:
        yield launcher.ports
    finally:
        launcher.cleanup()


def ours(seconds: float, probe_every: int, big_share: float = BIG_SHARE) -> float:
    a, b = free_ports()
    with tempfile.TemporaryDirectory() as out:
        opts = Options(host="127.0.0.1", port=a, second_port=b, duration=seconds, seed=1, out=Path(out),
                       allow_motion=True, launch=LAUNCH, probe_every=probe_every, big_share=big_share)  # fmt: skip
        campaign = Campaign(opts)
        campaign.run()
        return campaign.stats.rate


# ---------------------------------------------------------------------------------------------- boofuzz


def _boofuzz_field(bf: object, f: FieldDef, prefix: str) -> None:
    """The boofuzz primitives of one field (big-endian, guide 6.2)."""
    name = f"{prefix}{f.name}"  # boofuzz names are paths: no dots inside a name
    if f.is_group:
        bf.s_dword(1, name=f"{name}_count", endian=">")  # type: ignore[attr-defined]
        for g in f.fields:
            _boofuzz_field(bf, g, f"{name}_")
        return
    if f.type in ("STRING", "XML"):
        bf.s_size(f"data.{name}_text", length=4, endian=">", fuzzable=True, name=f"{name}_length")  # type: ignore[attr-defined]
        with bf.s_block(f"{name}_text"):  # type: ignore[attr-defined]
            bf.s_string("fuzz", name=f"{name}_value")  # type: ignore[attr-defined]
        return
    for k in range(f.repeat or 1):
        n = f"{name}{k}" if f.repeat else name
        value = f.const if f.const is not None else 0
        if f.type in ("BYTE", "BOOL"):
            bf.s_byte(value, name=n)  # type: ignore[attr-defined]
        elif f.type == "INT16":
            bf.s_word(value, name=n, endian=">")  # type: ignore[attr-defined]
        elif f.type == "INT":
            bf.s_dword(value, name=n, endian=">")  # type: ignore[attr-defined]
        else:
            bf.s_qword(0, name=n, endian=">")  # type: ignore[attr-defined]


def boofuzz_requests(bf: object) -> list[object]:
    """One boofuzz request per request telegram with a known layout (CMD_EXIT and CMD_SHUTDOWN_HOST left out,
    as pltf fuzz leaves them out)."""
    out = []
    bf.blocks.REQUESTS.clear()  # type: ignore[attr-defined]  # boofuzz keeps requests in a global registry
    for t in load_telegrams():
        if not t.layout_known or t.request is None or t.name in ("CMD_EXIT", "CMD_SHUTDOWN_HOST"):
            continue
        bf.s_initialize(t.name)  # type: ignore[attr-defined]
        bf.s_static(b"\xff\x01\xfe\x02", name="header")  # type: ignore[attr-defined]
        bf.s_size("data", length=4, endian=">", fuzzable=True, name="length")  # type: ignore[attr-defined]
        with bf.s_block("data"):  # type: ignore[attr-defined]
            bf.s_byte(t.id, name="id", fuzzable=False)  # type: ignore[attr-defined]
            for f in t.request:
                _boofuzz_field(bf, f, "")
        out.append(bf.s_get(t.name))  # type: ignore[attr-defined]
    return out


def run_boofuzz(seconds: float) -> float:
    import boofuzz as bf

    with reference_server() as (port, _), tempfile.TemporaryDirectory() as tmp:
        session = bf.Session(
            target=bf.Target(connection=bf.TCPSocketConnection("127.0.0.1", port)),
            sleep_time=0,
            restart_sleep_time=0,
            receive_data_after_each_request=False,
            receive_data_after_fuzz=False,
            check_data_received_each_request=False,
            web_port=None,
            fuzz_loggers=[bf.FuzzLoggerText(file_handle=io.StringIO())],
            db_filename=str(Path(tmp) / "boofuzz.db"),
            crash_threshold_element=10**9,
            crash_threshold_request=10**9,
        )
        for request in boofuzz_requests(bf):
            session.connect(request)
        counted = {"n": 0}
        original = session._fuzz_current_case
        t0 = time.monotonic()
        stop = t0 + seconds

        def counting(*args: object, **kwargs: object) -> object:
            if time.monotonic() >= stop:
                raise _Done  # boofuzz logs it and re-raises: the run ends
            counted["n"] += 1
            return original(*args, **kwargs)

        session._fuzz_current_case = counting  # type: ignore[method-assign]
        with contextlib.suppress(_Done):
            thread_safe_run(session)
        return counted["n"] / (time.monotonic() - t0)


class _Done(Exception):
    """Raised from boofuzz's post-test-case callback to end its run at the deadline."""


def thread_safe_run(session: object) -> None:
    """``session.fuzz()``, with boofuzz's stdout chatter swallowed."""
    with contextlib.redirect_stdout(io.StringIO()):
        session.fuzz()  # type: ignore[attr-defined]


@benchmark()
def cases_per_second(config: Config) -> list[Row]:
    """pltf fuzz vs boofuzz: test cases per second against the reference server (same telegrams)."""
    seconds = 2.0 if config.quick else 10.0
    repeats = 1 if config.quick else 3
    samples: dict[str, list[float]] = {OURS: [], OURS_STRICT: [], OURS_NATURAL: [], BOOFUZZ: []}
    for _ in range(repeats):  # interleaved, so a noisy spell on the machine hits every subject
        samples[OURS].append(ours(seconds, probe_every=4))
        samples[OURS_STRICT].append(ours(seconds, probe_every=1))
        samples[OURS_NATURAL].append(ours(seconds, probe_every=4, big_share=1.0))
        samples[BOOFUZZ].append(run_boofuzz(seconds))
    rates = {k: statistics.median(v) for k, v in samples.items()}
    name = "fuzz.cases_per_second"
    return [
        make_row(name, OURS, "cases_per_second", rates[OURS], "cases/s", higher_is_better=True,
                 target=Target("value", ">=", RATE_TARGET)),
        make_row(name, OURS, "cases_per_second", rates[OURS], "cases/s", higher_is_better=True,
                 baseline_subject=BOOFUZZ, baseline_value=rates[BOOFUZZ],
                 target=Target("ratio", "<=", 1 / SPEEDUP_TARGET)),
        make_row(name, OURS_STRICT, "cases_per_second", rates[OURS_STRICT], "cases/s", higher_is_better=True,
                 baseline_subject=BOOFUZZ, baseline_value=rates[BOOFUZZ]),
        make_row(name, OURS_NATURAL, "cases_per_second", rates[OURS_NATURAL], "cases/s", higher_is_better=True,
                 baseline_subject=BOOFUZZ, baseline_value=rates[BOOFUZZ]),
        make_row(name, BOOFUZZ, "cases_per_second", rates[BOOFUZZ], "cases/s", higher_is_better=True),
    ]  # fmt: skip


__all__ = ["boofuzz_requests", "cases_per_second"]
