"""Start a reference server for the suite: as a subprocess (tests, demo, mutants) or in-process (differential).

Rules:
- The subprocess is ``python -m pltf.reference_server --ports 0,0 ...`` (or the mutant bootstrap
  ``python -m pltf.conformance_tests.mutants.serve MUTANT ...``); its ports are read from its log lines
  ``server started at port N``. The data dir is a fresh temporary directory unless one is given (the server
  seeds it from fixtures/).
- In-process, the server runs its asyncio loop in a daemon thread (pltf.reference_server.network.serve with
  ``handle_signals=False``) and is stopped through the loop, never by killing the process.
- Both are context managers; ``stop`` ends only the process or thread they started.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

_STARTED = re.compile(r"server started at port (\d+)")


class LaunchError(RuntimeError):
    pass


class ServerProcess:
    """The reference server (or a mutant of it) as a child process on two ephemeral ports."""

    def __init__(self, *, time_scale: float = 10.0, seed: int = 1, data_dir: str | Path | None = None,
                 mutant: str | None = None, extra: Sequence[str] = (), startup_timeout: float = 20.0) -> None:
        self.time_scale, self.seed, self.mutant = time_scale, seed, mutant
        self._tmp = None if data_dir is not None else tempfile.TemporaryDirectory(prefix="pltf-conform-")
        self.data_dir = Path(data_dir) if data_dir is not None else Path(self._tmp.name) / "data"  # type: ignore[union-attr]
        self.extra = list(extra)
        self.startup_timeout = startup_timeout
        self.proc: subprocess.Popen[str] | None = None
        self.ports: list[int] = []
        self.log_lines: list[str] = []
        self._reader: threading.Thread | None = None

    def command(self) -> list[str]:
        args = ["--ports", "0,0", "--data-dir", str(self.data_dir), "--time-scale", f"{self.time_scale:g}",
                "--seed", str(self.seed), *self.extra]
        if self.mutant:
            return [sys.executable, "-m", "pltf.conformance_tests.mutants.serve", self.mutant, *args]
        return [sys.executable, "-m", "pltf.reference_server", *args]

    def start(self) -> ServerProcess:
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.proc = subprocess.Popen(self.command(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                     env=env)
        ready = threading.Event()

        def read() -> None:
            assert self.proc is not None and self.proc.stdout is not None
            for line in self.proc.stdout:
                self.log_lines.append(line.rstrip("\n"))
                m = _STARTED.search(line)
                if m:
                    self.ports.append(int(m.group(1)))
                    if len(self.ports) == 2:
                        ready.set()
            ready.set()

        self._reader = threading.Thread(target=read, daemon=True, name="server-log")
        self._reader.start()
        ready.wait(self.startup_timeout)
        if len(self.ports) < 2:
            self.stop()
            tail = "\n".join(self.log_lines[-15:])
            raise LaunchError(f"the server did not start ({' '.join(self.command())}):\n{tail}")
        return self

    @property
    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def stop(self, timeout: float = 10.0) -> int | None:
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        if self._reader is not None:
            self._reader.join(2.0)
        if self.proc.stdout is not None:
            self.proc.stdout.close()
        code = self.proc.returncode
        if self._tmp is not None:
            self._tmp.cleanup()
            self._tmp = None
        return code

    def __enter__(self) -> ServerProcess:
        return self.start() if self.proc is None else self

    def __exit__(self, *exc: object) -> None:
        self.stop()


class InProcessServer:
    """The reference server in a thread of this process (used by the differential mode)."""

    def __init__(self, *, time_scale: float = 10.0, seed: int = 1, data_dir: str | Path | None = None) -> None:
        self.time_scale, self.seed = time_scale, seed
        self._tmp = None if data_dir is not None else tempfile.TemporaryDirectory(prefix="pltf-diff-")
        self.data_dir = Path(data_dir) if data_dir is not None else Path(self._tmp.name) / "data"  # type: ignore[union-attr]
        self.ports: list[int] = []
        self._server: Any = None
        self._loop: Any = None
        self._thread: threading.Thread | None = None
        self._error: BaseException | None = None
        self._log_level = logging.NOTSET

    def start(self) -> InProcessServer:
        import asyncio

        from pltf.reference_server import network
        from pltf.reference_server.cli import build_platform
        from pltf.reference_server.storage import Storage

        log = logging.getLogger("pltf.server")
        self._log_level = log.level
        log.setLevel(logging.CRITICAL)  # its log lines are not the suite's output
        storage = Storage(self.data_dir)
        storage.seed_from_fixtures()
        platform = build_platform(storage, self.seed)  # what ``pltf serve`` runs
        ready = threading.Event()

        def on_ready(server: Any) -> None:
            self._server, self._loop = server, asyncio.get_running_loop()
            self.ports = list(server.ports)
            ready.set()

        def main() -> None:
            try:
                asyncio.run(network.serve(platform, "127.0.0.1", [0, 0], self.time_scale, ready=on_ready,
                                          handle_signals=False))
            except BaseException as exc:
                self._error = exc
            finally:
                platform.close()  # its CAN bus
                ready.set()

        self._thread = threading.Thread(target=main, daemon=True, name="reference-server")
        self._thread.start()
        ready.wait(20.0)
        if not self.ports:
            raise LaunchError(f"in-process reference server did not start: {self._error!r}")
        return self

    def stop(self) -> None:
        if self._loop is not None and self._server is not None:
            with contextlib.suppress(RuntimeError):
                self._loop.call_soon_threadsafe(self._server.stop)
        if self._thread is not None:
            self._thread.join(10.0)
        logging.getLogger("pltf.server").setLevel(self._log_level)
        if self._tmp is not None:
            self._tmp.cleanup()
            self._tmp = None

    def __enter__(self) -> InProcessServer:
        return self.start() if not self.ports else self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def wait_port_closed(host: str, port: int, within: float) -> bool:
    """True when nothing accepts connections on ``port`` within ``within`` seconds."""
    import socket

    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        try:
            with socket.create_connection((host, port), timeout=0.5):
                pass
        except OSError:
            return True
        time.sleep(0.05)
    return False
