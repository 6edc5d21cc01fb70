"""The optional ground-truth layer (issue 19): the reference server's fault-control channel, read only.

Rules:
- Only the channel's queries ``pose`` and ``faults`` are sent (fake_hardware/control_channel.py): the GUI shows
  the true pose beside the estimate and the injected faults, and never injects one itself.
- A tab asks with ``{"op": "truth", "control": "HOST:PORT"}``; it gets one reader, stopped when the tab goes or
  asks again. The reader polls every ``PERIOD`` s and sends ``{"event": "truth", "control", "time", "true",
  "estimate", "faults"}``; a channel that is not there or stops answering is said in words (``truth_lost``, with
  ``detail``) and tried again every ``RETRY`` s. Nothing else depends on it: the GUI works the same without it.
- The channel listens on loopback only, so the reader connects only to a loopback address (a page cannot make
  the gateway talk to other hosts through it).
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import json
from typing import Any

from pltf.gui.link import Send, parse_target

PERIOD = 0.2  # s
RETRY = 2.0  # s
TIMEOUT = 2.0  # s for a connection or an answer


def loopback(control: str) -> tuple[str, int]:
    """HOST:PORT of a loopback address, else ValueError with the reason."""
    host, port = parse_target(control)
    if host != "localhost":
        try:
            if not ipaddress.ip_address(host).is_loopback:
                raise ValueError(f"{control}: the control channel is read on a loopback address only")
        except ValueError as exc:
            raise ValueError(f"{control}: the control channel is read on a loopback address only") from exc
    return host, port


class TruthReader:
    def __init__(self, control: str, send: Send) -> None:
        self.control = control
        self.host, self.port = loopback(control)
        self.send = send
        self._task: asyncio.Task[None] | None = asyncio.get_running_loop().create_task(self._run())

    def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            self._task = None

    async def _run(self) -> None:
        while True:
            try:
                await self._serve()
            except (OSError, TimeoutError, ValueError, KeyError) as exc:
                self.send(
                    {
                        "event": "truth_lost",
                        "control": self.control,
                        "detail": str(exc) or type(exc).__name__,
                        "message": f"control channel {self.control}: {str(exc) or type(exc).__name__}",
                    }
                )
            await asyncio.sleep(RETRY)

    async def _serve(self) -> None:
        reader, writer = await asyncio.wait_for(asyncio.open_connection(self.host, self.port), TIMEOUT)
        try:
            while True:
                pose = await self._ask(reader, writer, "pose")
                faults = await self._ask(reader, writer, "faults")
                self.send(
                    {
                        "event": "truth",
                        "control": self.control,
                        "time": pose.get("time"),
                        "true": pose["true"],
                        "estimate": pose.get("estimate"),
                        "faults": faults.get("active", []),
                    }
                )
                await asyncio.sleep(PERIOD)
        finally:
            writer.close()
            with contextlib.suppress(OSError):
                await writer.wait_closed()

    @staticmethod
    async def _ask(reader: asyncio.StreamReader, writer: asyncio.StreamWriter, query: str) -> dict[str, Any]:
        writer.write(query.encode() + b"\n")
        await writer.drain()
        line = await asyncio.wait_for(reader.readline(), TIMEOUT)
        if not line:
            raise ConnectionResetError("the control channel closed the connection")
        answer = json.loads(line)
        if not isinstance(answer, dict) or not answer.get("ok"):
            raise ValueError(f"the control channel answered {line[:120]!r} to {query!r}")
        return answer
