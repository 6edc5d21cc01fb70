"""Fixtures of the reference server tests: a server in a background thread or a process, a blocking client.

The end-to-end tests talk to a real server over real TCP on ephemeral ports. ``ServerThread`` runs the
asyncio shell (pltf.reference_server.network.serve) in its own thread and event loop; the tests that need a
separate process (exit status, signals, SIGKILL) start ``python -m pltf.reference_server`` instead.
``ServerThread(..., hardware=factory)`` gives the platform the fake hardware (reference_server.hardware_link);
``control=True`` starts the fault-control channel on 127.0.0.1 too (``control_port``).
"""

from __future__ import annotations

import asyncio
import json
import re
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import can
import pytest

from pltf.fake_hardware import candb
from pltf.reference_server import hardware_link
from pltf.reference_server.control import ControlServer, start_control
from pltf.reference_server.hardware_link import HardwareFactory
from pltf.reference_server.motion_api import MotionFactory
from pltf.reference_server.network import Server, serve
from pltf.reference_server.platform import Platform
from pltf.reference_server.program_api import ProgramFactory
from pltf.reference_server.storage import Storage
from pltf.spec.codec import REQUESTS, TelegramDecoder, encode
from pltf.spec.parameters import ParameterStore
from pltf.spec.telegram import Telegram
from tests.reference_server.helpers import REPO, wait_for

TIME_SCALE = 20.0
S = TypeVar("S", bound="ServerThread")

if TYPE_CHECKING:  # the scenario servers import this module (at run time the fixtures import them)
    from tests.reference_server.world.scenarios import SteppedServer, WorldServer


class ServerThread:
    """The real network shell with its own event loop in a daemon thread."""

    def __init__(
        self,
        data_dir: Path,
        time_scale: float = TIME_SCALE,
        *,
        hardware: HardwareFactory | None = None,
        motion: MotionFactory | None = None,
        program: ProgramFactory | None = None,
        control: bool = False,
        params: dict[str, str] | None = None,
        **options: Any,
    ) -> None:
        storage = Storage(data_dir)
        storage.seed_from_fixtures()
        store = ParameterStore(startup=params)  # ``params``: the parameter file's values (read-only ones too)
        self.platform = Platform(storage, seed=1, motion=motion, program=program, hardware=hardware, parameters=store)
        self.time_scale = time_scale
        self.options = options
        self.control = control
        self.control_server: ControlServer | None = None
        self.server: Server | None = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self.exit_code: int | None = None
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._main, name="reference-server", daemon=True)

    def _main(self) -> None:
        def ready(server: Server) -> None:
            self.server, self.loop = server, asyncio.get_running_loop()
            if self.control:
                start_control(self.platform, 0, self._control_started)(server)
            self._ready.set()

        self.exit_code = asyncio.run(
            serve(
                self.platform, "127.0.0.1", [0, 0], self.time_scale, ready=ready, handle_signals=False, **self.options
            )
        )
        self._ready.set()

    def _control_started(self, control: ControlServer) -> None:
        self.control_server = control

    @property
    def control_port(self) -> int:
        assert self.control_server is not None, "ServerThread(control=True) starts the control channel"
        return self.control_server.port

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
        self.platform.close()

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


# ---- the scenario tests' servers (test_scenarios_*.py): the world as motion model, over real TCP
@pytest.fixture
def world_server(data_dir: Path) -> Iterator[WorldServer]:
    """Free running at the scenarios' accelerated time scale."""
    from tests.reference_server.world.scenarios import WorldServer

    yield from _running(WorldServer(data_dir))


@pytest.fixture
def stepped_server(data_dir: Path) -> Iterator[SteppedServer]:
    """Simulated time moves only when the test advances it (control periods)."""
    from tests.reference_server.world.scenarios import SteppedServer

    yield from _running(SteppedServer(data_dir))


@pytest.fixture
def hardware_server(data_dir: Path) -> Iterator[SteppedServer]:
    """Stepped, with the fake hardware (CAN boards) between the platform and its wheels."""
    from tests.reference_server.world.scenarios import SteppedServer

    yield from _running(SteppedServer(data_dir, hardware=True))


def _running(srv: S) -> Iterator[S]:
    srv.start()
    try:
        yield srv
    finally:
        srv.stop()


# ---- the server as a separate process
STARTED = re.compile(r"server started at port (\d+)")


class ServerProcess:
    """``python -m pltf.reference_server`` (or ``pltf serve``); without the fake hardware unless ``hardware=True``
    (the process tests are about storage, signals and exit codes, and time the server's work)."""

    def __init__(
        self,
        data_dir: Path,
        log_path: Path,
        *extra: str,
        module: str = "pltf.reference_server",
        hardware: bool = False,
    ) -> None:
        self.log_path = log_path
        cmd = [sys.executable, "-m", module]
        if module == "pltf.cli.main":
            cmd.append("serve")
        cmd += ["--ports", "0,0", "--data-dir", str(data_dir), "--time-scale", str(TIME_SCALE), *extra]
        if not hardware:
            cmd.append("--no-hardware")
        log_path.parent.mkdir(parents=True, exist_ok=True)
        self.log_file = log_path.open("wb")
        self.proc = subprocess.Popen(cmd, cwd=REPO, stdout=self.log_file, stderr=subprocess.STDOUT)
        try:
            self.ports = [int(p) for p in wait_for(self._ports, timeout=20)]
        except BaseException:  # not started in time: no server outlives its test
            self.kill()
            raise

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


# ---- the fake hardware from outside (test_hw_*.py): bytes on the socket (spec.codec), frames on the virtual CAN
# bus decoded with spec/can/pltf.dbc, JSON lines of the control channel's TCP port; no platform object is read.

STATUS_BOARDS = (
    "relay_status",
    "io_status",
    "motor_right_status",
    "motor_left_status",
    "us_status",
    "radar_status",
    "gyro_status",
)
MODE_VEL = 3  # MotionMode.MODE_MOTION_VEL
EM_NOT_ACTIVE, EM_ACTIVE, EM_RESET = 0, 1, 2
OP_READY, OP_RUNNING, OP_BREAKED, OP_NOT_INIT = 0, 1, 2, 3


class Sniffer:
    """A plain python-can virtual bus on the server's channel; every frame it hears must be in the database."""

    def __init__(self, channel: str) -> None:
        self.bus = can.Bus(interface="virtual", channel=channel, preserve_timestamps=True)
        self.heard: list[tuple[str, dict[str, Any], can.Message]] = []
        self._mark = 0

    def collect(self) -> list[tuple[str, dict[str, Any], can.Message]]:
        """The frames heard since the last call, decoded with the database (application ids as 'APP')."""
        out = []
        while (frame := self.bus.recv(timeout=0)) is not None:
            msg = candb.message_by_id(frame.arbitration_id)
            if msg is None:
                assert frame.arbitration_id in candb.APPLICATION_IDS, f"unknown CAN id 0x{frame.arbitration_id:03X}"
                out.append(("APP", {"data": bytes(frame.data)}, frame))
                continue
            assert len(frame.data) == msg.length, msg.name
            out.append((msg.name, dict(msg.decode(bytes(frame.data), decode_choices=False)), frame))
        self.heard += out
        return out

    def mark(self) -> None:
        """From now on: ``wait`` looks only at frames heard after this call."""
        self.collect()
        self._mark = len(self.heard)

    def wait(
        self, name: str, pred: Callable[[dict[str, Any]], bool] = lambda s: True, timeout: float = 5.0
    ) -> dict[str, Any]:
        """The signals of the first frame ``name`` since the last ``mark`` for which ``pred`` holds."""
        deadline = time.monotonic() + timeout
        seen = self._mark
        while True:
            self.collect()
            for n, signals, _ in self.heard[seen:]:
                if n == name and pred(signals):
                    return signals
            seen = len(self.heard)
            assert time.monotonic() < deadline, f"no {name} frame matching on the bus"
            time.sleep(0.005)

    def names(self, seconds: float) -> set[str]:
        """The message names heard during ``seconds`` of wall time from now."""
        self.collect()
        time.sleep(seconds)
        return {n for n, _, _ in self.collect()}

    def close(self) -> None:
        self.bus.shutdown()


class Control:
    """A client of the fault-control channel: one line out, one JSON object back."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5.0)
        self.file = self.sock.makefile("rwb")

    def __call__(self, line: str) -> dict[str, Any]:
        self.file.write(line.encode() + b"\n")
        self.file.flush()
        reply: dict[str, Any] = json.loads(self.file.readline())
        assert reply["ok"], f"{line}: {reply}"
        return reply

    def close(self) -> None:
        self.file.close()
        self.sock.close()


class Rig:
    """A started server with hardware, a raw client, the sniffer and the control channel."""

    def __init__(self, srv: ServerThread) -> None:
        self.srv = srv
        self.client = Client(srv.ports[0])
        assert srv.platform.hardware is not None
        self.sniffer = Sniffer(srv.platform.hardware.hw.channel)  # only the channel's name is read
        self.control = Control(srv.control_port)

    def send(self, name: str, **fields: Any) -> None:
        self.client.send(getattr(REQUESTS, name)(**fields))

    def get(self, name: str, **fields: Any) -> Any:
        return self.client.request(getattr(REQUESTS, name)(**fields))

    def status(self) -> Any:
        return self.client.status()

    def wait(
        self,
        pred: Callable[[Any], bool],
        what: str,
        timeout: float = 10.0,
        *,
        keep: Any = None,
        ask: str = "CMD_GET_STATUS",
    ) -> Any:
        """Poll ``ask`` (GET_STATUS) until ``pred`` holds for its reply; ``keep``: a (name, fields) command re-sent
        at every poll (a velocity command lives only VelWatchdogTime)."""
        deadline = time.monotonic() + timeout
        while True:
            if keep is not None:
                self.send(keep[0], **keep[1])
            st = self.get(ask)
            if pred(st):
                return st
            assert time.monotonic() < deadline, f"timed out waiting for {what} (last {st}); log: {self.log()[-12:]}"
            time.sleep(0.005)

    def wait_messages(self, pred: Callable[[Any], bool], delete: int = 0, timeout: float = 10.0) -> Any:
        """CMD_GET_CAN_MESSAGES until ``pred(messages)`` holds (with ``delete``); those messages."""
        deadline = time.monotonic() + timeout
        while True:
            msgs = self.get("CMD_GET_CAN_MESSAGES", delete=delete).messages
            if pred(msgs):
                return msgs
            assert time.monotonic() < deadline, f"timed out waiting for CAN messages: {msgs[-3:]}"
            time.sleep(0.01)

    def log(self) -> list[str]:
        return [e[0] for e in self.get("CMD_GET_DEBUG_DATA").protocol_queue]

    def wait_log(self, text: str, timeout: float = 10.0) -> str:
        deadline = time.monotonic() + timeout
        while True:
            for line in self.log():
                if text in line:
                    return line
            assert time.monotonic() < deadline, f"no log line with {text!r}: {self.log()[-8:]}"
            time.sleep(0.01)

    def bring_up(self) -> Any:
        self.send("CMD_CONNECT_TO_PLTF")
        self.send("CMD_INIT_PLTF")
        return self.wait(lambda s: s.operation_state == OP_READY, "state Ready")

    def run_vel(self) -> Any:
        """Ready -> MODE_MOTION_VEL -> Running."""
        self.send("CMD_SET_MODE", mode=MODE_VEL)
        self.send("CMD_START")
        return self.wait(lambda s: s.operation_state == OP_RUNNING, "state Running")

    def close(self) -> None:
        self.control.close()
        self.sniffer.close()
        self.client.close()


@contextmanager
def rig(
    data_dir: Path,
    motion: MotionFactory | None = None,
    up: bool = True,
    params: dict[str, str] | None = None,
    **hw: Any,
) -> Iterator[Rig]:
    srv = ServerThread(
        data_dir, hardware=hardware_link.factory(**hw), motion=motion, control=True, params=params
    ).start()
    r = Rig(srv)
    try:
        if up:
            r.bring_up()
        yield r
    finally:
        r.close()
        srv.stop()
