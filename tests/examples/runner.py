"""Running the examples as a user runs them: ``Example`` reads a subprocess' output line by line while it runs, so
a test can react to what the example says (restore a map after a refusal, release a key)."""

from __future__ import annotations

import os
import queue
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tests.clients.client_fakes import LiveServer

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples"
TIME_SCALE = 5.0  # fast enough for short tests, slow enough for the server to keep up on a loaded machine


def target(server: LiveServer) -> str:
    return f"127.0.0.1:{server.ports[0]}"


class Example:
    """One example running as a subprocess; its standard output read line by line in a thread, its standard error
    collected by another. Use it as a context manager (or call ``close``): the process is killed if still running."""

    def __init__(self, cmd: Sequence[str], **popen: Any) -> None:
        self.cmd = list(cmd)
        self.proc = subprocess.Popen(
            self.cmd,
            cwd=REPO,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, "PYTHONUNBUFFERED": "1"},
            **popen,
        )
        self.lines: list[str] = []
        self._queue: queue.Queue[str | None] = queue.Queue()
        self._err: list[str] = []
        self._threads = [
            threading.Thread(target=self._read, daemon=True),
            threading.Thread(target=self._read_err, daemon=True),
        ]
        for t in self._threads:
            t.start()

    def __enter__(self) -> Example:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self._queue.put(line.rstrip("\n"))
        self._queue.put(None)

    def _read_err(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            self._err.append(line)

    def expect(self, prefix: str, timeout: float = 30.0) -> str:
        """The next line that starts with ``prefix`` (earlier lines are kept in ``lines``)."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                line = self._queue.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                raise AssertionError(f"no line {prefix!r} within {timeout} s; so far: {self.lines}") from None
            if line is None:
                self._queue.put(None)
                raise AssertionError(f"ended before a line {prefix!r}: {self.lines}\n{self.stderr()}")
            self.lines.append(line)
            if line.startswith(prefix):
                return line

    def finish(self, timeout: float = 30.0) -> int:
        """Wait for the end; every line it printed is in ``lines`` afterwards, its standard error in ``stderr()``."""
        try:
            code = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.close()
            raise AssertionError(f"{self.cmd[1:3]} still running after {timeout} s: {self.lines}") from None
        for t in self._threads:
            t.join(5)
        while (line := self._queue.get_nowait()) is not None:
            self.lines.append(line)
        self._queue.put(None)
        return code

    def stderr(self) -> str:
        return "".join(self._err)

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait(10)
        for t in self._threads:
            t.join(5)
        for pipe in (self.proc.stdin, self.proc.stdout, self.proc.stderr):
            if pipe is not None:
                pipe.close()


def python_example(name: str, *args: str) -> list[str]:
    return [sys.executable, str(EXAMPLES / name), *args]
