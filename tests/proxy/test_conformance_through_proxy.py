"""Through ``pltf proxy`` the conformance suite judges the reference server exactly as it does direct: case by
case, the same verdicts. The proxy runs as a user runs it (``pltf proxy``, its own process, recording).

Default tier: the cases a proxy could change (split, slow and coalesced frames, bad headers, a huge length,
half-closes, a second client, reconnects, closing, replies in order). ``slow``: the whole standard tier.
A case whose verdicts differ is run again on both sides (twice at most): on a loaded machine the suite's timing
cases can flake direct as well; only a difference that holds is one.
"""

from __future__ import annotations

import re
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from pltf.conformance_tests.catalogue import Case, Tier, Verdict, load_all, select
from pltf.conformance_tests.runner import Runner
from pltf.conformance_tests.target import Config
from pltf.harness import launch
from pltf.proxy.session import read_session

TIME_SCALE = 10.0
LISTENING = re.compile(r"proxy listening at [\d.]+:(\d+)")


@contextmanager
def pltf_proxy(target_ports: list[int], record: Path) -> Iterator[list[int]]:
    """``pltf proxy`` in front of both ports, recording; its listening ports; stopped with SIGINT (Ctrl-C)."""
    cmd = [
        sys.executable,
        "-m",
        "pltf.cli.main",
        "proxy",
        "--listen",
        "127.0.0.1:0",
        "--target",
        f"127.0.0.1:{target_ports[0]}",
        "--second",
        f"0:{target_ports[1]}",
        "--quiet",
        "--record",
        str(record),
    ]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        ports: list[int] = []
        deadline = time.monotonic() + 60
        assert proc.stdout is not None
        while len(ports) < 2:
            line = proc.stdout.readline()
            why = proc.stderr.read() if not line and proc.stderr else ""
            assert line and time.monotonic() < deadline, f"pltf proxy did not start: {why}"
            if m := LISTENING.search(line):
                ports.append(int(m.group(1)))
        yield ports
    finally:
        proc.send_signal(2)
        try:
            _, err = proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
            raise
        assert proc.returncode == 0, err
        assert "proxy stopped:" in err


def verdicts(cases: list[Case], proxied: bool, record: Path) -> dict[str, Verdict]:
    with launch.reference(time_scale=TIME_SCALE) as server:
        if not proxied:
            ports = server.ports
            return _run(ports, cases)
        with pltf_proxy(server.ports, record) as ports:
            return _run(ports, cases)


def _run(ports: list[int], cases: list[Case]) -> dict[str, Verdict]:
    config = Config("127.0.0.1", ports[0], ports[1], time_scale=TIME_SCALE, simulator=True, allow_shutdown=True)
    result = Runner(config, cases).run()
    return {r.case.id: r.verdict for r in result.results}


def _compare(cases: list[Case], tmp_path: Path) -> None:
    direct = {k: {v} for k, v in verdicts(cases, False, tmp_path / "unused.jsonl").items()}
    proxied = {k: {v} for k, v in verdicts(cases, True, tmp_path / "session.jsonl").items()}
    assert len(direct) == len(cases)
    session = read_session(tmp_path / "session.jsonl")  # the proxy recorded what went through it
    assert sum(r.kind == "open" for r in session.records) >= min(len(cases), 10)  # cases also share sessions
    assert any(r.error and r.error.startswith("BadHeader") for r in session.records)
    for attempt in range(2):
        again = [c for c in cases if not direct[c.id] & proxied[c.id]]
        if not again:
            break
        for k, v in verdicts(again, False, tmp_path / "unused.jsonl").items():
            direct[k].add(v)
        for k, v in verdicts(again, True, tmp_path / f"again{attempt}.jsonl").items():
            proxied[k].add(v)
    differ = {k: (direct[k], proxied[k]) for k in direct if not direct[k] & proxied[k]}
    assert not differ, differ


WIRE_CASES = (
    "6.2/framing/header-and-length",
    "6.2/framing/split-every-offset",
    "6.2/framing/slow-sender",
    "6.2/framing/coalesced",
    "6.2/framing/bad-header",
    "6.2/framing/huge-length",
    "6.2/framing/half-close-partial",
    "6.2/framing/half-close-complete",
    "6.1/ports/both-serve",
    "6.1/ports/second-client-turned-away",
    "6.1/ports/reconnect",
    "6.1/replies/in-order",
    "6.3/CMD_CLOSE_SOCKET/closes",
)


def test_the_cases_a_proxy_could_change_judge_the_same_through_it(tmp_path: Path) -> None:
    every = load_all()
    _compare(select([every[c] for c in WIRE_CASES], tier=Tier.STANDARD), tmp_path)


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_the_standard_tier_judges_the_same_through_the_proxy(tmp_path: Path) -> None:
    _compare(select(load_all().values(), tier=Tier.STANDARD), tmp_path)
