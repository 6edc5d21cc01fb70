"""Start (and restart) the target ourselves, so that a death can be minimized against fresh instances.

Rules:
- The command is a template: ``{port}``, ``{second_port}`` and ``{ports}`` ("A,B") come from the target
  address; ``{tmpdir}`` is a fresh empty directory per start (a fresh data directory for the server).
- Port 0 asks for ephemeral ports: the target must then log ``server started at port N`` once per port, in
  port order (the reference server's convention); we read them from its merged stdout/stderr.
- Every wait is bounded; ``stop`` ends only the process we started (terminate, then kill).
- The target's output goes to a log file (a pipe would cost us a reader thread); ``output`` is its tail.
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import IO

STARTED = re.compile(r"server started at port (\d+)")
START_TIMEOUT = 20.0


class LaunchError(RuntimeError):
    """The target could not be started (the harness's problem: exit status 2)."""


class Launcher:
    def __init__(self, template: str, host: str, port: int, second_port: int) -> None:
        self.template, self.host = template, host
        self.want = (port, second_port)
        self.ports = (port, second_port)
        self.proc: subprocess.Popen[bytes] | None = None
        self._log: IO[bytes] | None = None
        self._tmp: str | None = None
        self.starts = 0

    def command(self) -> list[str]:
        a, b = self.want
        self._tmp = tempfile.mkdtemp(prefix="pltf-fuzz-target-")
        text = self.template.format(port=a, second_port=b, ports=f"{a},{b}", tmpdir=self._tmp)
        return shlex.split(text)

    def start(self) -> tuple[int, int]:
        self.cleanup()
        self._log = tempfile.NamedTemporaryFile(prefix="pltf-fuzz-target-", suffix=".log", delete=False)  # noqa: SIM115
        try:
            self.proc = subprocess.Popen(
                self.command(), stdout=self._log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL
            )
        except OSError as exc:
            raise LaunchError(f"cannot start the target: {exc}") from None
        self.starts += 1
        if 0 in self.want:
            deadline = time.monotonic() + START_TIMEOUT
            seen: list[int] = []
            while len(seen) < 2 and self.alive() and time.monotonic() < deadline:
                time.sleep(0.02)
                seen = [int(m) for m in STARTED.findall(self._read_log())]
            if len(seen) < 2:
                tail = " | ".join(self.output[-5:])
                self.stop()
                raise LaunchError(f"the target did not report two ports ('server started at port N'): {tail}")
            self.ports = (seen[0], seen[1])
        else:
            self.ports = self.want
            self._wait_listening()
        return self.ports

    def _read_log(self, limit: int = 1 << 20) -> str:
        if self._log is None:
            return ""
        with open(self._log.name, "rb") as fh:
            fh.seek(0, 2)
            size = fh.tell()
            fh.seek(max(0, size - limit))
            return fh.read().decode("utf-8", "replace")

    @property
    def output(self) -> list[str]:
        """The last lines the target wrote (stdout and stderr)."""
        return self._read_log(1 << 16).splitlines()[-200:]

    def _wait_listening(self) -> None:
        import socket

        deadline = time.monotonic() + START_TIMEOUT
        while time.monotonic() < deadline and self.alive():
            try:
                socket.create_connection((self.host, self.ports[1]), timeout=0.5).close()
                return
            except OSError:
                time.sleep(0.05)
        raise LaunchError(f"the target does not listen on {self.host}:{self.ports[1]}")

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def exit_code(self) -> int | None:
        return None if self.proc is None else self.proc.poll()

    def stop(self) -> None:
        proc, self.proc = self.proc, None
        if proc is not None and proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(2)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(5)
        if self._tmp is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None

    def cleanup(self) -> None:
        """Stop the target and remove its log."""
        self.stop()
        if self._log is not None:
            self._log.close()
            Path(self._log.name).unlink(missing_ok=True)
            self._log = None
