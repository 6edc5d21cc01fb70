"""Start (and restart) the target ourselves, so that a death can be minimized against fresh instances.

Rules:
- The command is a template: ``{port}``, ``{second_port}`` and ``{ports}`` ("A,B") come from the target
  address; ``{tmpdir}`` is a fresh empty directory per start (a fresh data directory for the server).
- Port 0 asks for ephemeral ports: the target must then log ``server started at port N`` once per port, in
  port order (the reference server's convention); we read them from its merged stdout/stderr.
- Every wait is bounded; ``stop`` ends only the process we started (terminate, then kill).
- The target's output goes to a log file (a pipe would cost us a reader thread); ``output`` is its tail.
- The toolkit's launcher is ``pltf.zoo.launch``; this one adds warm spares for the minimiser and raises its
  ``LaunchError``. Warm spares (``spares = True``, ephemeral ports only): while one instance is in use the next
  one starts, so that delta debugging, which wants a fresh instance per test, waits for a start only when the
  spare is not yet up. A spare that is not taken is stopped with the launcher.
"""

from __future__ import annotations

import re
import shlex
import shutil
import socket
import subprocess
import tempfile
import time
from pathlib import Path
from typing import IO

from pltf.zoo.launch import LaunchError  # the toolkit's one error for a target that could not be started

STARTED = re.compile(r"server started at port (\d+)")
START_TIMEOUT = 20.0


class Instance:
    """One started target process, its log and its data directory."""

    def __init__(self, template: str, want: tuple[int, int]) -> None:
        a, b = want
        self.tmp = tempfile.mkdtemp(prefix="pltf-fuzz-target-")
        self.log: IO[bytes] = tempfile.NamedTemporaryFile(prefix="pltf-fuzz-target-", suffix=".log", delete=False)  # noqa: SIM115
        command = shlex.split(template.format(port=a, second_port=b, ports=f"{a},{b}", tmpdir=self.tmp))
        try:
            self.proc = subprocess.Popen(command, stdout=self.log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        except OSError as exc:
            self.cleanup()
            raise LaunchError(f"cannot start the target: {exc}") from None
        self.ports = want

    def alive(self) -> bool:
        return self.proc.poll() is None

    def read_log(self, limit: int = 1 << 20) -> str:
        with open(self.log.name, "rb") as fh:
            fh.seek(0, 2)
            size = fh.tell()
            fh.seek(max(0, size - limit))
            return fh.read().decode("utf-8", "replace")

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(2)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)
        shutil.rmtree(self.tmp, ignore_errors=True)

    def cleanup(self) -> None:
        if hasattr(self, "proc"):
            self.stop()
        shutil.rmtree(self.tmp, ignore_errors=True)
        self.log.close()
        Path(self.log.name).unlink(missing_ok=True)


class Launcher:
    def __init__(self, template: str, host: str, port: int, second_port: int) -> None:
        self.template, self.host = template, host
        self.want = (port, second_port)
        self.ports = (port, second_port)
        self.current: Instance | None = None
        self.spare: Instance | None = None
        self.spares = False
        self.starts = 0

    @property
    def proc(self) -> subprocess.Popen[bytes] | None:
        return self.current.proc if self.current is not None else None

    def start(self) -> tuple[int, int]:
        """A fresh instance (the warm spare when there is one), its ports once it serves them."""
        self.cleanup_current()
        inst = self.spare if self.spare is not None and self.spare.alive() else None
        if inst is None and self.spare is not None:
            self.spare.cleanup()
        self.spare = None
        inst = inst or Instance(self.template, self.want)
        self.current = inst
        self.starts += 1
        try:
            self.ports = self._ready(inst)
        finally:
            if self.spares and 0 in self.want:
                self.spare = Instance(self.template, self.want)
        return self.ports

    def _ready(self, inst: Instance) -> tuple[int, int]:
        deadline = time.monotonic() + START_TIMEOUT
        if 0 in self.want:
            seen: list[int] = []
            while len(seen) < 2 and inst.alive() and time.monotonic() < deadline:
                seen = [int(m) for m in STARTED.findall(inst.read_log())]
                if len(seen) < 2:
                    time.sleep(0.02)
            if len(seen) < 2:
                tail = " | ".join(self.output[-5:])
                self.stop()
                raise LaunchError(f"the target did not report two ports ('server started at port N'): {tail}")
            return seen[0], seen[1]
        while time.monotonic() < deadline and inst.alive():
            try:
                socket.create_connection((self.host, self.want[1]), timeout=0.5).close()
                return self.want
            except OSError:
                time.sleep(0.05)
        raise LaunchError(f"the target does not listen on {self.host}:{self.want[1]}")

    @property
    def output(self) -> list[str]:
        """The last lines the target wrote (stdout and stderr)."""
        return self.current.read_log(1 << 16).splitlines()[-200:] if self.current is not None else []

    def alive(self) -> bool:
        return self.current is not None and self.current.alive()

    def exit_code(self) -> int | None:
        return None if self.current is None else self.current.proc.poll()

    def stop(self) -> None:
        """Stop the instance in use (its log stays readable until the next start)."""
        if self.current is not None:
            self.current.stop()

    def cleanup_current(self) -> None:
        if self.current is not None:
            self.current.cleanup()
            self.current = None

    def no_spares(self) -> None:
        self.spares = False
        if self.spare is not None:
            self.spare.cleanup()
            self.spare = None

    def cleanup(self) -> None:
        """Stop every instance and remove the logs."""
        self.cleanup_current()
        if self.spare is not None:
            self.spare.cleanup()
            self.spare = None
