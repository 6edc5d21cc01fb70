"""The Go emulator (emulator/, issue 17): it builds with its own script, its Go tests pass, it is clean under gofmt
and go vet, and the toolkit's launcher starts it on ephemeral ports and reads them from its log, as it does the
reference server's. Skipped (listed by -ra) only when the Go toolchain is absent, and then only outside make test
(tests/emulator_gate.py: PLTF_REQUIRE_EMULATOR=1 makes it a failure).
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
from pathlib import Path

import pytest

from pltf.harness.launch import Launcher
from pltf.spec.codec import TelegramDecoder, build, encode
from tests.emulator_gate import missing

REPO = Path(__file__).resolve().parents[2]
EMULATOR = REPO / "emulator"
TIMEOUT = 420


def _run(cmd: list[str], timeout: float = TIMEOUT) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, GOTOOLCHAIN="local")
    return subprocess.run(cmd, cwd=EMULATOR, env=env, capture_output=True, text=True, timeout=timeout, check=False)


@pytest.fixture(scope="module")
def binary() -> Path:
    if shutil.which("go") is None:
        missing("TOOLCHAIN MISSING for the emulator: go not on PATH")
    proc = _run(["sh", "build.sh"])
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return EMULATOR / "bin" / "emulator"


def test_go_tests_pass(binary: Path) -> None:
    proc = _run(["go", "test", "./..."])
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-4000:]


def test_go_vet_clean(binary: Path) -> None:
    proc = _run(["go", "vet", "./..."])
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-4000:]


def test_gofmt_clean(binary: Path) -> None:
    proc = _run(["gofmt", "-l", "."])
    assert proc.returncode == 0 and proc.stdout == "", proc.stdout + proc.stderr


def _get_status(port: int) -> object:
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(encode(build("request", "CMD_GET_STATUS")))
        dec = TelegramDecoder("reply")
        while (reply := dec.next_telegram()) is None:
            data = s.recv(65536)
            assert data, "the emulator closed the connection"
            dec.receive_data(data)
        return reply


def test_the_launcher_reads_its_ports(binary: Path) -> None:
    launcher = Launcher(f"{binary} --ports {{ports}} --data-dir {{tmpdir}} --reply-delay-ms 0", "127.0.0.1", 0, 0)
    try:
        ports = launcher.start()
        assert ports[0] != ports[1] and 0 not in ports
        for port in ports:
            reply = _get_status(port)
            assert reply.NAME == "CMD_GET_STATUS" and reply.operation_state == 3  # type: ignore[attr-defined]
    finally:
        launcher.cleanup()
    assert not launcher.alive()
