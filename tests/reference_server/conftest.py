"""Fixtures of the reference server tests: a server in a background thread or a process, a blocking client.

The end-to-end tests talk to a real server over real TCP on ephemeral ports. ``ServerThread`` runs the
asyncio shell (reference_server.network.serve) in its own thread and event loop; the tests that need a
separate process (exit status, signals, SIGKILL) start ``python -m reference_server`` instead.
"""

from __future__ import annotations

import asyncio
import re
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from reference_server.network import Server, serve
from reference_server.platform import Platform
from reference_server.storage import Storage
from spec.codec import REQUESTS, TelegramDecoder, encode
from spec.telegram import Telegram
from tests.reference_server.helpers import REPO, wait_for

TIME_SCALE = 20.0


class ServerThread:
    """The real network shell with its own event loop in a daemon thread."""

    def __init__(self, data_dir: Path, time_scale: float = TIME_SCALE, **options: Any) -> None:
        storage = Storage(data_dir)
        storage.seed_from_fixtures()
        self.platform = Platform(storage, seed=1)
        self.time_scale = time_scale
        self.options = options
        self.server: Server | None = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self.exit_code: int | None = None
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._main, name="reference-server", daemon=True)

    def _main(self) -> None:
        def ready(server: Server) -> None:
            self.server, self.loop = server, asyncio.get_running_loop()
            self._ready.set()

        self.exit_code = asyncio.run(
            serve(self.platform, "127.0.0.1", [0, 0], self.time_scale, ready=ready, handle_signals=False,
                  **self.options)
        )  # fmt: skip
        self._ready.set()

    def start(self) -> ServerThread:
        self._thread.start()
        assert self._ready.wait(10), "server did not start"
        return self

    @property
    def ports(self) -> list[int]:
        assert self.server is not None
        return self.server.ports

    def call(self, func: Any, *args: Any) -> Any:
        """Run ``func(*args)`` on the server's loop (the platform is not thread-safe) and return its result."""
        assert self.loop is not None

        async def run() -> Any:
            return func(*args)

        return asyncio.run_coroutine_threadsafe(run(), self.loop).result(5)

    def stop(self) -> None:
        if self.loop is not None and self._thread.is_alive():
            self.loop.call_soon_threadsafe(self.server.stop)  # type: ignore[union-attr]
        self._thread.join(10)
        assert not self._thread.is_alive(), "server thread did not stop"

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()


class Client:
    """A blocking test client: frames out, reply telegrams in."""

    def __init__(self, port: int, timeout: float = 5.0) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.decoder = TelegramDecoder("reply")

    def send(self, *telegrams: Telegram) -> None:
        self.sock.sendall(b"".join(encode(t) for t in telegrams))

    def send_raw(self, data: bytes) -> None:
        self.sock.sendall(data)

    def receive(self) -> Telegram:
        while True:
            telegram = self.decoder.next_telegram()
            if telegram is not None:
                return telegram
            data = self.sock.recv(65536)
            if not data:
                raise ConnectionError("server closed the connection")
            self.decoder.receive_data(data)

    def request(self, telegram: Telegram) -> Any:
        self.send(telegram)
        reply = self.receive()
        assert reply.NAME == telegram.NAME
        return reply

    def status(self) -> Any:
        return self.request(REQUESTS.CMD_GET_STATUS())

    def closed_by_server(self, timeout: float = 5.0) -> bool:
        """True when the server closes the connection within ``timeout`` (nothing else may arrive)."""
        self.sock.settimeout(timeout)
        try:
            data = self.sock.recv(65536)
        except (ConnectionResetError, BrokenPipeError):
            return True
        except TimeoutError:
            return False
        assert data == b"", f"unexpected bytes {data[:32].hex()}"
        return True

    def pending_bytes(self, wait: float = 0.05) -> bytes:
        self.sock.settimeout(wait)
        try:
            return self.sock.recv(65536)
        except TimeoutError:
            return b""
        finally:
            self.sock.settimeout(5.0)

    def close(self) -> None:
        self.sock.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@pytest.fixture
def data_dir(tmp_path: Path) -> Path:
    return tmp_path / "data"


@pytest.fixture
def server(data_dir: Path) -> Iterator[ServerThread]:
    srv = ServerThread(data_dir).start()
    try:
        yield srv
    finally:
        srv.stop()


# ---- the server as a separate process
STARTED = re.compile(r"server started at port (\d+)")


class ServerProcess:
    def __init__(self, data_dir: Path, log_path: Path, *extra: str, module: str = "reference_server") -> None:
        self.log_path = log_path
        cmd = [sys.executable, "-m", module]
        if module == "pltf_cli.main":
            cmd.append("serve")
        cmd += ["--ports", "0,0", "--data-dir", str(data_dir), "--time-scale", str(TIME_SCALE), *extra]
        log_path.parent.mkdir(parents=True, exist_ok=True)
        self.log_file = log_path.open("wb")
        self.proc = subprocess.Popen(cmd, cwd=REPO, stdout=self.log_file, stderr=subprocess.STDOUT)
        self.ports = [int(p) for p in wait_for(self._ports, timeout=20)]

    def _ports(self) -> list[str] | None:
        if self.proc.poll() is not None:
            raise AssertionError(f"server exited with {self.proc.returncode}:\n{self.log()}")
        ports = STARTED.findall(self.log())
        return ports if len(ports) == 2 and "system state" in self.log() else None

    def log(self) -> str:
        return self.log_path.read_text(encoding="utf-8", errors="replace")

    def wait(self, timeout: float = 10.0) -> int:
        try:
            return self.proc.wait(timeout)
        finally:
            self.log_file.close()

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
        self.wait()
