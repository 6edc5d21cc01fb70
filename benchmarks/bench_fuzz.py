"""Fuzzing rate: ``pltf fuzz`` versus boofuzz driving the same telegrams, on three targets.

Targets, each started fresh per subject and run (own process, own data dir, log level ERROR so that neither pays
for per-connection INFO lines):

- ``reference server``: ``python -m pltf.reference_server``. It reads what a port's client sent before it judges a
  newcomer (erratum E-WIRE-007), so clients may follow each other back to back.
- ``zoo slow-release``: the reference server behind the zoo member ``slow-release`` (``python -m pltf.zoo
  slow-release --serve reference``), a TCP relay that frees a port 5-50 ms after its client left and turns
  newcomers away until then (FIN): what a foreign platform behind a proxy does. No read-ahead helps here.
- ``zoo accept-once``: the zoo member ``accept-once``: newcomers wait in the listen backlog until the port's
  client has gone (the E-WIRE-007 alternative reading).
- ``zoo fin-ends-session`` and ``zoo slow-accept``: rows 1 and 5 of the zoo's behaviour matrix (issue 32): the
  client's FIN ends the session (the fuzzer then half-closes only once its replies came), and an accept loop on a
  100 ms timer.

Subjects, each for the same wall time (10 s), three times, interleaved; the median rate is reported:

- ``pltf fuzz``: the network campaign of ``pltf.fuzz.engine`` as ``pltf fuzz --allow-motion`` runs it (state
  preludes, batching of the cases the codec accepts, a fresh connection per case it refuses, every unit opened by
  the GET_STATUS that proves it was served). A case is counted when the target served it: one turned away runs
  again and counts once. ``false findings`` counts its findings and unconfirmed suspicions: every target here
  conforms, so each one would be false.
- ``pltf fuzz, no pipelining`` (reference server): each port's next case connects only once the last has gone: the
  rate without the server's read-ahead.
- ``pltf fuzz, natural mix (--big-share 1)`` (reference server): every drawn case over 1 MiB kept (by default the
  scheduler keeps a quarter of them: ``pltf.fuzz.schedule``).
- ``boofuzz``: one boofuzz request per request telegram of the spec (header and length as boofuzz primitives, the
  length computed by ``s_size`` over the data block, every field fuzzable with boofuzz's own value library), a
  ``Session`` on a TCP connection with no sleeps and no receive, the web UI off, results in a throw-away sqlite
  file: boofuzz as one would set it up for speed. It opens a connection per case and never reads, so it does not
  notice a newcomer turned away: behind a zoo member its rate counts only the connections the member served (the
  member's own count, ``--stats``); its own count is in ``boofuzz, as it counts``.

What bounds the rates, beside them (``benchmarks.proc_cpu``, the target's process group read from /proc while it
runs): ``target CPU per case`` (ms of the target's CPU per case it served, ours with boofuzz's as its baseline) and
``target busy`` (the cores it kept busy): how much of the ratio is the target's cost and how much each tool's own
(benchmarks/results/zoo.md, runs 7 and 8: on a free machine ours keeps the reference server three quarters busy,
boofuzz a fifth),
and ``ratio ceiling, target never idle``: the ratio to boofuzz the target would give if its threads (the reference
server's one loop; a zoo member's relay and the server behind it, at most the machine's cores) never waited -
the most any fuzzer with this mix could reach on the machine of the run; ``share of the ratio ceiling``: the
measured ratio over that ceiling.

A case is one test case: one boofuzz mutation, one ``pltf fuzz`` case. Targets: >= 3,000 cases/s against the
reference server, >= 10x boofuzz (time ratio <= 0.1) on every target, no false finding.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from benchmarks.harness import Config, Row, Target, benchmark, make_row
from benchmarks.proc_cpu import group_cpu, pgid_of
from pltf.fuzz.engine import Campaign, Options
from pltf.fuzz.options import Stats
from pltf.fuzz.schedule import BIG_SHARE
from pltf.harness.launch import Launcher
from pltf.harness.ports import free_ports
from pltf.spec.model import FieldDef, load_telegrams

OURS = "pltf fuzz"
OURS_PLAIN = "pltf fuzz, no pipelining"
OURS_NATURAL = "pltf fuzz, natural mix (--big-share 1)"
BOOFUZZ = "boofuzz"
BOOFUZZ_NOMINAL = "boofuzz, as it counts"
FALSE = "pltf fuzz false findings"
RATE_TARGET = 3000.0
SPEEDUP_TARGET = 10.0
REFERENCE = (
    f"{sys.executable} -m pltf.reference_server --ports {{ports}} --data-dir {{tmpdir}} --seed 1 --log-level ERROR"
)
ZOO = f"{sys.executable} -m pltf.zoo {{member}} --serve reference --ports {{{{ports}}}} --seed 1 --log-level ERROR"
TARGETS = {
    "reference server": REFERENCE,
    "zoo slow-release": ZOO.format(member="slow-release"),
    "zoo accept-once": ZOO.format(member="accept-once"),
    # the behaviour matrix (zoo/README.md, issue 32): row 1, the client's FIN ends the session; row 5, a 100 ms
    # accept timer
    "zoo fin-ends-session": ZOO.format(member="fin-ends-session"),
    "zoo slow-accept": ZOO.format(member="slow-accept"),
}
DIRECT = "reference server"
CPU_PER_CASE = "target CPU per case"
BUSY = "target busy"
CEILING = "ratio ceiling, target never idle"
SHARE = "share of the ratio ceiling"
# the threads that serve a case: the reference server is one asyncio loop; a zoo member adds its relay's loop
TARGET_THREADS = dict.fromkeys(TARGETS, 2) | {DIRECT: 1}


class TargetCpu:
    """The target's CPU while a subject drives it, from readings of its process group (``proc_cpu``): the first
    and the last reading taken while it lived, with the cases served at each."""

    def __init__(self) -> None:
        self.pgid: int | None = None  # the target's process group, once ``watch`` knows it
        self.first: tuple[float, float, int] | None = None  # (monotonic time, CPU seconds, cases)
        self.last: tuple[float, float, int] | None = None

    def watch(self, pid: int) -> None:
        self.pgid = pgid_of(pid)

    def read(self, cases: int) -> None:
        cpu = None if self.pgid is None else group_cpu(self.pgid)
        if not cpu:  # no /proc, or the group is gone (a stopped target reads as nothing)
            return
        reading = (time.monotonic(), cpu, cases)
        self.first = self.first or reading
        self.last = reading

    def figures(self, cases: float | None = None) -> tuple[float, float] | None:
        """(ms of target CPU per case served, cores the target kept busy) between the readings; ``cases``: the
        cases served between them where the readings do not know it."""
        if self.first is None or self.last is None:
            return None
        (t0, c0, n0), (t1, c1, n1) = self.first, self.last
        served = n1 - n0 if cases is None else cases
        if served <= 0 or t1 <= t0:
            return None
        return (c1 - c0) / served * 1e3, (c1 - c0) / (t1 - t0)


@contextlib.contextmanager
def started(launch: str, stats: Path | None = None) -> Iterator[Launcher]:
    """The target started on two free ports (a zoo member writing its counts to ``stats`` when it ends)."""
    a, b = free_ports()
    launcher = Launcher(launch + (f" --stats {stats}" if stats is not None else ""), "127.0.0.1", a, b)
    launcher.start()
    try:
        yield launcher
    finally:
        launcher.cleanup()


def ours(
    launch: str, seconds: float, pipeline: bool = True, big_share: float = BIG_SHARE
) -> tuple[float, int, tuple[float, float] | None]:
    """(cases per second, findings and unconfirmed suspicions, the target's CPU figures of ``TargetCpu``) of a
    campaign of ``seconds``."""
    a, b = free_ports()
    with tempfile.TemporaryDirectory() as out:
        opts = Options(
            host="127.0.0.1",
            port=a,
            second_port=b,
            duration=seconds,
            seed=1,
            out=Path(out),
            allow_motion=True,
            launch=launch,
            pipeline=pipeline,
            big_share=big_share,
        )
        campaign = Campaign(opts)
        cpu = TargetCpu()

        def tick(st: Stats) -> None:  # every 0.25 s while it runs (and once after the target is stopped)
            if cpu.pgid is None and campaign.launcher is not None and campaign.launcher.proc is not None:
                cpu.watch(campaign.launcher.proc.pid)
            cpu.read(st.cases)

        campaign.on_tick = tick
        campaign.run()
        st = campaign.stats
        way = ("kept connection" + (", paced" if st.ways else "")) if st.dear else "fresh connections"
        load = os.getloadavg()[0]
        print(
            f"  {' '.join(launch.split()[2:4])}: {st.rate:,.0f} cases/s, {way} (trial: {st.ways}), load {load:.1f}",
            file=sys.stderr,
        )
        return st.rate, len(st.findings) + len(st.unconfirmed), cpu.figures()


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


def run_boofuzz(launch: str, seconds: float) -> tuple[float, float, tuple[float, float] | None]:
    """(cases per second as boofuzz counts them, cases per second the target served, the target's CPU figures of
    ``TargetCpu``)."""
    import boofuzz as bf

    proxy = launch != REFERENCE
    with tempfile.TemporaryDirectory() as tmp:
        stats = Path(tmp) / "served.json"
        with started(launch, stats if proxy else None) as target:
            cpu = TargetCpu()
            if target.proc is not None:
                cpu.watch(target.proc.pid)
            cpu.read(0)
            nominal, elapsed = _boofuzz(bf, target.ports[0], seconds, Path(tmp))
            cpu.read(0)  # a member counts what it served when it ends: the cases come below
        served = _served(stats) / elapsed if proxy else nominal
        return nominal, served, cpu.figures(served * elapsed)


def _served(stats: Path) -> float:
    """The connections a zoo member served on its first port, from its ``--stats`` file (0 when it wrote none)."""
    return float(json.loads(stats.read_text())["served"][0]) if stats.exists() else 0.0


def _boofuzz(bf: object, port: int, seconds: float, tmp: Path) -> tuple[float, float]:
    """boofuzz against ``port`` for ``seconds``: (cases per second, seconds)."""
    session = bf.Session(  # type: ignore[attr-defined]
        target=bf.Target(connection=bf.TCPSocketConnection("127.0.0.1", port)),  # type: ignore[attr-defined]
        sleep_time=0,
        restart_sleep_time=0,
        receive_data_after_each_request=False,
        receive_data_after_fuzz=False,
        check_data_received_each_request=False,
        web_port=None,
        fuzz_loggers=[bf.FuzzLoggerText(file_handle=io.StringIO())],  # type: ignore[attr-defined]
        db_filename=str(tmp / "boofuzz.db"),
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

    session._fuzz_current_case = counting
    with contextlib.suppress(_Done):
        thread_safe_run(session)
    elapsed = time.monotonic() - t0
    return counted["n"] / elapsed, elapsed


class _Done(Exception):
    """Raised from boofuzz's post-test-case callback to end its run at the deadline."""


def thread_safe_run(session: object) -> None:
    """``session.fuzz()``, with boofuzz's stdout chatter swallowed."""
    with contextlib.redirect_stdout(io.StringIO()):
        session.fuzz()  # type: ignore[attr-defined]


@benchmark()
def cases_per_second(config: Config) -> list[Row]:
    """pltf fuzz vs boofuzz: test cases per second on the reference server and two foreign targets."""
    seconds = 2.0 if config.quick else 10.0
    repeats = 1 if config.quick else 3
    samples: dict[tuple[str, str], list[float]] = {}
    false: dict[str, int] = dict.fromkeys(TARGETS, 0)

    def add(target: str, subject: str, value: float) -> None:
        samples.setdefault((target, subject), []).append(value)

    def add_cpu(target: str, subject: str, figures: tuple[float, float] | None) -> None:
        if figures is not None:
            samples.setdefault((target, f"{CPU_PER_CASE}, {subject}"), []).append(figures[0])
            samples.setdefault((target, f"{BUSY}, {subject}"), []).append(figures[1])

    for _ in range(repeats):  # interleaved, so a noisy spell on the machine hits every subject
        for target, launch in TARGETS.items():
            rate, wrong, cpu = ours(launch, seconds)
            add(target, OURS, rate)
            add_cpu(target, OURS, cpu)
            false[target] += wrong
            if target == DIRECT:
                add(target, OURS_PLAIN, ours(launch, seconds, pipeline=False)[0])
                add(target, OURS_NATURAL, ours(launch, seconds, big_share=1.0)[0])
            nominal, served, cpu = run_boofuzz(launch, seconds)
            print(f"  boofuzz ({target}): {served:,.1f} cases/s served, load {os.getloadavg()[0]:.1f}", file=sys.stderr)
            add(target, BOOFUZZ, served)
            add_cpu(target, BOOFUZZ, cpu)
            if target != DIRECT:
                add(target, BOOFUZZ_NOMINAL, nominal)
    rates = {k: statistics.median(v) for k, v in samples.items()}
    name = "fuzz.cases_per_second"
    rows = [
        make_row(
            name,
            f"{OURS} ({DIRECT})",
            "cases_per_second",
            rates[DIRECT, OURS],
            "cases/s",
            higher_is_better=True,
            target=Target("value", ">=", RATE_TARGET),
        )
    ]
    for target in TARGETS:
        subjects = [s for t, s in rates if t == target and not s.startswith((CPU_PER_CASE, BUSY))]
        for subject in subjects:
            base = BOOFUZZ if subject != BOOFUZZ else None
            goal = Target("ratio", "<=", 1 / SPEEDUP_TARGET) if subject == OURS else None
            rows.append(
                make_row(
                    name,
                    f"{subject} ({target})",
                    "cases_per_second",
                    rates[target, subject],
                    "cases/s",
                    higher_is_better=True,
                    baseline_subject=base and f"{base} ({target})",
                    baseline_value=base and rates[target, base],
                    target=goal,
                )
            )
        rows.append(
            make_row(
                name,
                f"{FALSE} ({target})",
                "findings",
                false[target],
                "findings",
                higher_is_better=False,
                target=Target("value", "<=", 0),
            )
        )
    for target in TARGETS:
        if target != DIRECT:  # through a foreign target against the reference server directly
            rows.append(
                make_row(
                    name,
                    f"{OURS} ({target})",
                    "cases_per_second",
                    rates[target, OURS],
                    "cases/s",
                    higher_is_better=True,
                    baseline_subject=f"{OURS} ({DIRECT})",
                    baseline_value=rates[DIRECT, OURS],
                )
            )
    return rows + _cpu_rows(name, rates) + _ceiling_rows(name, rates)


def _cpu_rows(name: str, rates: dict[tuple[str, str], float]) -> list[Row]:
    """What bounds the rates: the target's CPU per case served (ratio: ours over boofuzz's) and the cores it kept
    busy, under each tool (the target's whole process group: a zoo member and the server behind it)."""
    rows = []
    for target in TARGETS:
        for metric, unit, key in ((CPU_PER_CASE, "ms", "cpu_per_case"), (BUSY, "cores", "busy_cores")):
            ours_key, base_key = (target, f"{metric}, {OURS}"), (target, f"{metric}, {BOOFUZZ}")
            if ours_key not in rates or base_key not in rates:
                continue  # no /proc here
            base = f"{base_key[1]} ({target})"
            per_case = metric == CPU_PER_CASE
            rows.append(make_row(name, base, key, rates[base_key], unit, higher_is_better=False))
            rows.append(
                make_row(
                    name,
                    f"{ours_key[1]} ({target})",
                    key,
                    rates[ours_key],
                    unit,
                    higher_is_better=False,
                    baseline_subject=base if per_case else None,
                    baseline_value=rates[base_key] if per_case else None,
                )
            )
    return rows


def ceiling(cpu_ms: float, threads: int, baseline_rate: float, cores: int) -> float:
    """The most times ``baseline_rate`` a target can serve when what a case costs it is ``cpu_ms`` of CPU and its
    ``threads`` (at most ``cores`` of them at once) never wait: the bound the target puts on the ratio, whatever
    the fuzzer does."""
    return min(threads, cores) / (cpu_ms / 1e3) / baseline_rate


def _ceiling_rows(name: str, rates: dict[tuple[str, str], float]) -> list[Row]:
    """Per target: the ratio to boofuzz that the target's CPU per case of ours allows (``ceiling``), beside the
    ratio target; a figure under it says the target, not the fuzzer, keeps the ratio under 10x."""
    rows = []
    for target in TARGETS:
        cpu_key = (target, f"{CPU_PER_CASE}, {OURS}")
        if cpu_key not in rates or not rates.get((target, BOOFUZZ)):
            continue  # no /proc here, or boofuzz served nothing
        value = ceiling(rates[cpu_key], TARGET_THREADS[target], rates[target, BOOFUZZ], os.cpu_count() or 1)
        rows.append(make_row(name, f"{CEILING} ({target})", "ratio_ceiling", value, "x boofuzz", higher_is_better=True))
        if rates.get((target, OURS)):  # how much of what the target allows the fuzzer reached
            share = rates[target, OURS] / rates[target, BOOFUZZ] / value
            rows.append(make_row(name, f"{SHARE} ({target})", "ceiling_share", share, "", higher_is_better=True))
    return rows


__all__ = ["boofuzz_requests", "cases_per_second", "ceiling"]
