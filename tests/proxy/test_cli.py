"""``pltf proxy`` on the command line: what a user gets wrong is one line and exit status 2."""

from __future__ import annotations

import socket
import subprocess
import sys
from pathlib import Path

import pytest

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
