"""``pltf proxy`` on the command line: what a user gets wrong is one line and exit status 2; with either forwarding
core it forwards and records a busy exchange, and Ctrl-C ends it with everything written."""

from __future__ import annotations

import re
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from pltf.proxy.session import read_session
from pltf.proxy.tap import FRAME
from pltf.spec.codec import REQUESTS, encode
from tests.proxy.helpers import read_exactly

ROOT = Path(__file__).resolve().parents[2]


def _pltf(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "pltf.cli.main", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--listen", "nowhere", "--target", "127.0.0.1:1"], "expected HOST:PORT"),
        (["--listen", "127.0.0.1:0", "--target", "127.0.0.1:1", "--second", "x"], "expected PORT or LISTEN_PORT"),
        (
            ["--listen", "127.0.0.1:0", "--target", "127.0.0.1:1", "--record", "/no/such/dir/s.jsonl"],
            "cannot write the recording: /no/such/dir/s.jsonl",
        ),
    ],
)
def test_user_errors_are_one_line(args: list[str], message: str) -> None:
    proc = _pltf("proxy", *args)
    assert proc.returncode == 2 and message in proc.stderr and "Traceback" not in proc.stderr, proc.stderr


def test_a_port_in_use_is_one_line() -> None:
    with socket.create_server(("127.0.0.1", 0)) as busy:
        proc = _pltf("proxy", "--listen", f"127.0.0.1:{busy.getsockname()[1]}", "--target", "127.0.0.1:1", "--quiet")
    assert proc.returncode == 2 and "pltf proxy: error: cannot listen on 127.0.0.1" in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("core", [[], ["--threads"]], ids=["c-loop", "threads"])
def test_a_busy_exchange_is_forwarded_recorded_in_order_and_ctrl_c_ends_it(core: list[str], tmp_path: Path) -> None:
    """500 request/reply round trips back to back through ``pltf proxy --record`` (the spin path of the C loop):
    every byte passes, Ctrl-C ends the proxy with status 0 within seconds, and the session holds each request
    before the reply it caused."""
    request, reply = encode(REQUESTS.CMD_STOP()), encode(REQUESTS.CMD_START())  # two valid frames, as the bytes
    session = tmp_path / "s.jsonl"
    with socket.create_server(("127.0.0.1", 0)) as target:
        target.settimeout(10)
        cmd = [sys.executable, "-m", "pltf.cli.main", "proxy", "--listen", "127.0.0.1:0", "--quiet", *core]
        cmd += ["--target", f"127.0.0.1:{target.getsockname()[1]}", "--record", str(session)]
        with subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) as proc:
            try:
                assert proc.stdout is not None
                port = re.search(r"listening at [\d.]+:(\d+)", proc.stdout.readline())
                assert port is not None
                with socket.create_connection(("127.0.0.1", int(port.group(1))), timeout=10) as client:
                    conn, _ = target.accept()
                    with conn:
                        for _ in range(500):
                            client.sendall(request)
                            assert read_exactly(conn, len(request)) == request
                            conn.sendall(reply)
                            assert read_exactly(client, len(reply)) == reply
                proc.send_signal(signal.SIGINT)
                _, err = proc.communicate(timeout=20)
            finally:
                proc.kill()
    assert proc.returncode == 0 and "Traceback" not in err, err
    assert "proxy stopped: 1 connections, 1000 frames" in err, err  # the summary, on stderr
    frames = [r for r in read_session(session).records if r.kind == FRAME]
    assert [(r.direction, r.raw) for r in frames] == [("request", request), ("reply", reply)] * 500
