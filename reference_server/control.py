"""The fault-control channel of the reference server: the line protocol of fake_hardware/control_channel.py on a
TCP port of the loopback interface (documented in fake_hardware/README.md, "Control channel").

Rules:
- A network module, like reference_server/network.py: sockets and asyncio live here; the protocol is parsed
  and dispatched without I/O by ``pltf.fake_hardware.control_channel``. Each request gets the simulated ``now`` of
  the server's clock; it runs on the server's event loop, so between two control periods, never during one.
- Loopback only (127.0.0.1): the channel unplugs boards and presses the emergency stop; it must never face a
  network. Port 0 takes any free port; the port is logged as "control channel started at port N".
- Started from ``network.serve(..., ready=...)`` (``start_control``): the socket is bound at once (so the port
  is known when ``ready`` returns), the listener runs as a task of the server's loop and ends with it.
- Queries beyond the hardware's: ``pose`` (the true and the estimated pose, erratum E-HW-023).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import socket
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from pltf.fake_hardware.control_channel import ControlChannel, ControlSession

if TYPE_CHECKING:
    from pltf.reference_server.network import Server
    from pltf.reference_server.platform import Platform

log = logging.getLogger("pltf.server")

HOST = "127.0.0.1"
READ_SIZE = 4096


class ControlServer:
    def __init__(self, platform: Platform, now: Callable[[], float], port: int = 0) -> None:
        if platform.hardware is None:
            raise ValueError("the control channel needs the fake hardware (no --no-hardware)")
        self.platform = platform
        self.now = now
        self.channel = ControlChannel(platform.hardware.hw, extra={"pose": self._pose})
        self.sock = socket.create_server((HOST, port), reuse_port=False)
        self.sock.setblocking(False)
        self.port: int = self.sock.getsockname()[1]
        self._task: asyncio.Task[None] | None = None
        self._clients: set[asyncio.StreamWriter] = set()

    def start(self) -> int:
        """Serve on the running loop; returns the port."""
        self._task = asyncio.get_running_loop().create_task(self._serve(), name="control-channel")
        log.info("control channel started at port %d (fault injection, loopback only)", self.port)
        return self.port

    async def _serve(self) -> None:
        server = await asyncio.start_server(self._client, sock=self.sock)
        try:
            async with server:
                await server.serve_forever()
        finally:
            for writer in list(self._clients):
                writer.close()

    def close(self) -> None:
        if self._task is not None:
            self._task.cancel()
        else:
            self.sock.close()

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        session = ControlSession(self.channel)
        self._clients.add(writer)
        try:
            while data := await reader.read(READ_SIZE):
                out = session.receive_data(data, self.now())
                self.platform.touch()  # a fault may show in the next status reply
                if out:
                    writer.write(out)
                    await writer.drain()
        except (ConnectionError, OSError):
            pass
        finally:
            self._clients.discard(writer)
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()

    def _pose(self, now: float) -> dict[str, Any]:
        m = self.platform.motion
        true, est = m.true_pose, m.pose
        return {"time": now, "true": [true.x, true.y, true.angle], "estimate": [est.x, est.y, est.angle]}


def start_control(
    platform: Platform, port: int, started: Callable[[ControlServer], None] | None = None
) -> Callable[[Server], None]:
    """A ``ready`` callback for ``network.serve`` that starts the control channel on the server's loop."""

    def ready(server: Server) -> None:
        control = ControlServer(platform, server.clock.now, port)
        control.start()
        if started is not None:
            started(control)

    return ready
