"""One TCP connection to one platform, shared by every browser tab that watches it.

Rules:
- Guide 4.2: "For each port one client is able to connect": the GUI holds ONE connection to ONE port (the
  guide's second port stays free for the user's application), whatever the number of tabs.
- Request frames from the tabs go out in arrival order; replies go back through ``routing.Router``.
- Connection events are JSON objects ``{"event": ..., "target": ..., "message": ...}`` sent to every tab:
  connecting, connected, unreachable, refused, turned_away, dropped, timeout, malformed, closed, retry.
  Every failure is said in words and followed by a reconnect with backoff while any tab wants the socket open.
  Besides the English ``message`` an event carries its parts as fields (``detail``: the system's or the codec's
  own words; ``timeout``, ``attempt``, ``delay``; a retry repeats its failure's ``reason`` and fields), so a tab
  words it in its own language (web/src/session/connwords.ts).
- A platform that closes the connection before sending a single byte has turned us away (erratum E-GUI-003;
  E-WIRE-007: a busy port accepts a second client and closes it at once).
- A request whose reply has not come within ``reply_timeout`` seconds ends the connection (the platform has
  stopped answering); a malformed reply does too (the stream is out of step).
- One tab at a time drives (control.py, issue 33): a command of a tab that does not hold control, or of any tab
  under ``read_only``, is refused here and never reaches the platform; each tab is told who drives (``control``).
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import logging
import time
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from typing import Any

from pltf.gui.control import COMMANDS, Control
from pltf.gui.routing import ANSWERED, BadRequest, Router
from pltf.spec.codec import FRAME_OVERHEAD
from pltf.spec.errors import RemoteProtocolError

log = logging.getLogger("pltf.gui")

CONNECT_TIMEOUT = 5.0  # s
REPLY_TIMEOUT = 5.0  # s a pending request may wait for its reply
BACKOFF = (0.5, 1.0, 2.0, 4.0, 8.0)  # s before the n-th reconnect; the last one repeats
IDLE_CLOSE = 5.0  # s the connection stays open after the last tab has gone
READ_SIZE = 1 << 16

Send = Callable[[bytes | dict[str, Any]], None]  # a tab's outlet: a reply frame or an event


@dataclass
class Stats:
    """What the TCP Client tab of the hardware monitor shows (guide 5.8), for the whole connection."""

    bytes_out: int = 0
    bytes_in: int = 0
    telegrams_out: int = 0
    telegrams_in: int = 0
    coalesced: int = 0
    errors: int = 0
    reconnects: int = 0
    rtt_ms: list[float] = field(default_factory=list)

    def snapshot(self) -> dict[str, Any]:
        rtts = sorted(self.rtt_ms[-200:])
        out = {k: v for k, v in vars(self).items() if k != "rtt_ms"}
        out["rtt_ms_median"] = rtts[len(rtts) // 2] if rtts else None
        out["rtt_ms_max"] = rtts[-1] if rtts else None
        return out


def parse_target(text: str) -> tuple[str, int]:
    """``HOST:PORT`` -> (host, port); ValueError with a one-line reason."""
    host, sep, port = text.strip().rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"expected HOST:PORT with a port 1..65535, got {text!r}")
    return host.strip("[]"), int(port)


class PlatformLink:
    """The connection to one target and the tabs attached to it."""

    def __init__(
        self,
        target: str,
        *,
        reply_timeout: float = REPLY_TIMEOUT,
        backoff: tuple[float, ...] = BACKOFF,
        on_idle: Callable[[PlatformLink], None] | None = None,
        read_only: bool = False,
    ) -> None:
        self.target = target
        self.host, self.port = parse_target(target)
        self.reply_timeout = reply_timeout
        self.backoff = backoff
        self.on_idle = on_idle
        self.tabs: dict[Hashable, Send] = {}
        self.router = Router()
        self.control = Control(read_only=read_only)
        self.stats = Stats()
        self.state = "closed"  # closed | connecting | connected | waiting
        self.want_open = False
        self.last_event: dict[str, Any] = {"event": "closed", "target": target, "message": "socket closed"}
        self._writer: asyncio.StreamWriter | None = None
        self._task: asyncio.Task[None] | None = None
        self._idle: asyncio.TimerHandle | None = None
        self._wake = asyncio.Event()
        self._failure = ""  # the last failure in words, repeated while waiting to reconnect
        self._reason = ""
        self._failure_fields: dict[str, Any] = {}

    # ---- tabs
    def attach(self, tab: Hashable, send: Send, label: str = "a tab") -> None:
        self.tabs[tab] = send
        self.control.join(tab, label)
        if self._idle is not None:
            self._idle.cancel()
            self._idle = None
        send(self.last_event)
        send({**self.control.view(tab), "target": self.target})

    def detach(self, tab: Hashable) -> None:
        self.tabs.pop(tab, None)
        self.router.forget(tab)
        if self.control.leave(tab):
            self._tell_control()
        if not self.tabs:
            self._idle = asyncio.get_running_loop().call_later(IDLE_CLOSE, self._close_idle)

    def _close_idle(self) -> None:
        self._idle = None
        if not self.tabs:
            self.close("no viewer left", by="idle")
            if self.on_idle is not None:
                self.on_idle(self)

    def _event(self, event: str, message: str, **extra: Any) -> None:
        self.last_event = {"event": event, "target": self.target, "message": message, **extra}
        (log.info if event in ("connecting", "connected", "closed") else log.warning)("%s: %s", self.target, message)
        for send in list(self.tabs.values()):
            send(self.last_event)

    # ---- who drives (issue 33)
    def _tell_control(self) -> None:
        for tab, send in list(self.tabs.items()):
            send({**self.control.view(tab), "target": self.target})

    def take(self, tab: Hashable) -> None:
        """Take control (an explicit action of the tab); refused under read-only."""
        if self.control.read_only:
            self._refuse(
                tab,
                "read_only",
                "Take control refused: this GUI is read-only (pltf gui --read-only)",
                telegram="Take control",
            )
            return
        if self.control.take(tab):
            log.info("%s: %s takes control", self.target, self.control.labels.get(tab, "a tab"))
            self._tell_control()

    def may_close(self, tab: Hashable) -> bool:
        """Close Socket ends the link for every tab: only the driver's, or anybody's while nobody drives."""
        refused = self.control.refusal(tab)
        if refused is not None and refused[0] == "viewer":
            self._refuse(tab, refused[0], f"Close Socket {refused[1]}", telegram="Close Socket")
            return False
        return True

    def _refuse(self, tab: Hashable, reason: str, message: str, telegram: str) -> None:
        """Tell the tab its command was refused (``reason``: "read_only" or "viewer"); a command has no reply,
        so nothing of the tab waits for it (``id`` None)."""
        send = self.tabs.get(tab)
        if send is not None:
            holder = self.control.view(tab)["holder"]
            event = {"event": "refused_command", "reason": reason, "telegram": telegram, "holder": holder, "id": None}
            send({**event, "target": self.target, "message": message})

    # ---- open / close (Socket menu, guide 5.2)
    def open(self) -> None:
        self.want_open = True
        if self._task is None or self._task.done():
            self._task = asyncio.get_running_loop().create_task(self._run(), name=f"link {self.target}")
        else:
            self._wake.set()  # skip the rest of a backoff wait

    def close(self, why: str = "socket closed", by: str = "") -> None:
        """Close Socket: the connection ends; the platform's operating mode is left alone (guide 5.2).
        ``by``: "viewer", "gateway" or "" (no viewer left), for the tabs' own wording."""
        self.want_open = False
        if self._task is not None:
            self._task.cancel()
            self._task = None
        self._drop_writer()
        self._fail_pending(why)
        self.state = "closed"
        self._event("closed", why, by=by)

    def _drop_writer(self) -> None:
        if self._writer is not None:
            self._writer.close()
            self._writer = None

    def _fail_pending(self, why: str) -> None:
        for entry in self.router.reset():
            for tab in entry.tabs:
                if tab in self.tabs:
                    self.tabs[tab]({"event": "lost", "target": self.target, "message": why, "id": entry.telegram_id})

    # ---- frames from tabs
    def submit(self, tab: Hashable, frame: bytes) -> None:
        send = self.tabs[tab]
        first = frame[FRAME_OVERHEAD] if len(frame) > FRAME_OVERHEAD else None
        answered = first if first in ANSWERED else None
        command = first in COMMANDS
        if command and (refused := self.control.refusal(tab)) is not None:
            name = COMMANDS[first] if first is not None else "the command"
            self._refuse(tab, refused[0], f"{name} {refused[1]}", telegram=name)
            return
        if self._writer is None or self.state != "connected":
            send({"event": "not_sent", "target": self.target, "message": "the socket is not open", "id": answered})
            return
        try:
            out = self.router.submit(tab, frame, time.monotonic())
        except BadRequest as exc:
            send({"event": "bad_request", "target": self.target, "message": str(exc), "id": answered})
            return
        if out is None:
            self.stats.coalesced += 1
            return
        self._writer.write(out)
        self.stats.bytes_out += len(out)
        self.stats.telegrams_out += 1
        if command and self.control.claim(tab):
            self._tell_control()

    # ---- the connection
    async def _run(self) -> None:
        attempt = 0
        me = asyncio.current_task()
        while self.want_open:
            attempt += 1
            served = await self._connect_and_serve(attempt)
            if self._task is not me:  # closed (and maybe opened again) while the cancellation was swallowed
                return
            self._drop_writer()
            self._fail_pending("connection lost")
            if not self.want_open:
                break
            if served:
                attempt = 1
            self.stats.reconnects += 1
            delay = self.backoff[min(attempt - 1, len(self.backoff) - 1)]
            self.state = "waiting"
            why = self._failure or "connection lost"
            self._event(
                "retry", f"{why}; reconnecting in {delay:g} s", delay=delay, reason=self._reason, **self._failure_fields
            )
            self._wake.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._wake.wait(), delay)

    async def _connect_and_serve(self, attempt: int) -> bool:
        """One connection; True when it had served (connected and received data) before it ended."""
        self.state = "connecting"
        self._event("connecting", f"connecting to {self.target} (attempt {attempt})", attempt=attempt)
        try:
            reader, writer = await asyncio.wait_for(asyncio.open_connection(self.host, self.port), CONNECT_TIMEOUT)
        except ConnectionRefusedError:
            self._fail("refused", f"{self.target} refused the connection: nothing listens on that port")
            return False
        except TimeoutError:
            self._fail(
                "unreachable",
                f"{self.target} did not answer the connection within {CONNECT_TIMEOUT:g} s",
                timeout=CONNECT_TIMEOUT,
            )
            return False
        except OSError as exc:
            self._fail("unreachable", f"{self.target} cannot be reached: {_reason(exc)}", detail=_reason(exc))
            return False
        self._writer = writer
        self.state = "connected"
        self._failure = self._reason = ""
        self._failure_fields = {}
        self._event("connected", f"connected to {self.target}")
        received = 0
        while True:
            try:
                data = await asyncio.wait_for(reader.read(READ_SIZE), self._read_timeout())
                closed_meanwhile = self._writer is not writer
            except TimeoutError:
                if self._overdue():
                    self._fail(
                        "timeout",
                        f"{self.target} stopped answering: no reply for {self.reply_timeout:g} s",
                        timeout=self.reply_timeout,
                    )
                    return received > 0
                continue
            except OSError as exc:
                self._fail("dropped", f"{self.target} dropped the connection: {_reason(exc)}", detail=_reason(exc))
                return received > 0
            if closed_meanwhile:
                # Close Socket while this read completed (its bytes or the platform's FIN after CMD_CLOSE_SOCKET):
                # Python 3.11's wait_for can hand back a read that finished as the task was cancelled; close() has
                # reset the router and said "socket closed", so the read belongs to nobody
                return received > 0
            if not data:
                if received == 0:
                    self._fail(
                        "turned_away",
                        f"{self.target} closed the connection at once: its port already "
                        "has a client (one client per port, guide 4.2)",
                    )
                    return False
                self._fail("dropped", f"{self.target} closed the connection")
                return True
            received += len(data)
            if not self._deliver(data):
                return True

    def _read_timeout(self) -> float:
        oldest = self.router.oldest()
        if oldest is None:
            return 0.5
        return max(0.01, oldest + self.reply_timeout - time.monotonic())

    def _overdue(self) -> bool:
        oldest = self.router.oldest()
        return oldest is not None and time.monotonic() - oldest >= self.reply_timeout

    def _deliver(self, data: bytes) -> bool:
        self.stats.bytes_in += len(data)
        now = time.monotonic()
        try:
            for frame, entry in self.router.receive_data(data):
                self.stats.telegrams_in += 1
                self.stats.rtt_ms.append((now - entry.sent_at) * 1000.0)
                del self.stats.rtt_ms[:-1000]
                for tab in entry.tabs:
                    send = self.tabs.get(tab)
                    if send is not None:
                        send(frame)
        except (RemoteProtocolError, ValueError) as exc:
            self._fail("malformed", f"{self.target} sent a malformed reply: {exc}", detail=str(exc))
            return False
        return True

    def _fail(self, event: str, message: str, **fields: Any) -> None:
        if self.state == "closed":  # a task whose cancellation was swallowed: Close Socket has had the last word
            return
        self.stats.errors += 1
        self._failure, self._reason, self._failure_fields = message, event, fields
        self._event(event, message, **fields)


def _reason(exc: OSError) -> str:
    if exc.errno is not None and exc.errno in errno.errorcode:
        return exc.strerror or errno.errorcode[exc.errno]
    return str(exc) or type(exc).__name__
