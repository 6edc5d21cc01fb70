"""One node's attachment to the CAN bus: a python-can bus plus the faults that can sit between them.

Rules:
- Every node (each board and the controller) owns one ``CanPort`` on its own python-can bus object, all on the
  same channel, as real nodes each have a transceiver. Nothing else touches the python-can bus.
- Sans-IO in spirit: ``send(frame, now)`` and ``poll(now)`` take simulated time and never block
  (``recv(timeout=0)``). A frame's timestamp is the simulated time it went on the bus.
- ``interface="virtual"`` opens ``SimVirtualBus``: python-can's virtual bus (same channel registry, so a plain
  virtual bus on the channel - a test's sniffer - sees and sends the same traffic) with a cheaper delivery:
  the sent frame itself is shared by all receivers (no copy; neither they nor the sender may mutate it after
  sending), a ``SimpleQueue`` inbox, and acceptance filtering at delivery (``CanPort.accept``: a board's
  inbox gets only the ids it handles, like a CAN controller's hardware filter; other interfaces deliver
  everything and the board ignores what it does not handle: python-can's software filters would end a
  ``recv(timeout=0)`` drain at the first frame they reject).
- Faults are plain attributes: ``connected`` (unplugged: nothing in, nothing out), ``bus_off`` (the same, and
  the port says so), ``loss`` / ``delay`` (this sender only) on top of the channel-wide ``BusConditions``.
  Delayed frames wait in the port and go out at the first ``send``/``poll`` at or after their due time.
"""

from __future__ import annotations

import queue
import random
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import can
from can.interfaces import virtual


@dataclass
class BusConditions:
    """Faults of the whole channel (every sender): frame loss probability and transmission delay (s)."""

    rng: random.Random = field(default_factory=lambda: random.Random(0))
    loss: float = 0.0
    delay: float = 0.0


class _Inbox(queue.SimpleQueue):  # type: ignore[type-arg]
    """A receiver's queue with its acceptance filter (None: every frame)."""

    accept: frozenset[int] | None = None


class SimVirtualBus(virtual.VirtualBus):
    """The virtual bus with simulated timestamps kept and a cheap fan-out (see the module rules)."""

    _filters_changed = 0  # a generation count of the acceptance filters of every SimVirtualBus

    def __init__(self, channel: str, **kwargs: Any) -> None:
        super().__init__(channel=channel, preserve_timestamps=True, **kwargs)
        inbox = _Inbox()
        with virtual.channels_lock:
            self.channel[self.channel.index(self.queue)] = inbox  # type: ignore[call-overload]
            self.queue = inbox  # type: ignore[assignment]
        self._members: list[Any] = []  # the channel's inboxes when ``_targets`` was computed
        self._generation = -1
        self._targets: tuple[tuple[Any, frozenset[int] | None], ...] = ()

    def accept(self, ids: frozenset[int] | None) -> None:
        """Deliver to this bus only frames with these identifiers (None: all)."""
        self.queue.accept = ids  # type: ignore[attr-defined]
        SimVirtualBus._filters_changed += 1  # every sender recomputes its targets

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self._check_if_open()
        msg.channel, msg.is_rx = self.channel_id, True  # shared by every receiver, not copied
        if self._members != self.channel or self._generation != SimVirtualBus._filters_changed:
            self._members = list(self.channel)  # a bus joined or left (a sniffer, a closed platform), or a filter
            self._generation = SimVirtualBus._filters_changed
            own = self.queue
            self._targets = tuple((q, getattr(q, "accept", None)) for q in self._members if q is not own)
        can_id = msg.arbitration_id
        for inbox, ids in self._targets:
            if ids is None or can_id in ids:
                inbox.put(msg)

    def drain(self) -> list[can.Message]:
        """Everything in the inbox, without blocking (the fast path of ``CanPort.poll``)."""
        self._check_if_open()
        q = self.queue
        if q.empty():  # most polls: found out without raising and catching queue.Empty
            return []
        out: list[can.Message] = []
        get = q.get_nowait
        try:
            while True:
                out.append(get())
        except queue.Empty:
            return out


def open_bus(interface: str, channel: str, **kwargs: Any) -> can.BusABC:
    """A python-can bus: ``SimVirtualBus`` for ``virtual``, else ``can.Bus`` (socketcan on vcan0, a real adapter)."""
    if interface == "virtual":
        return SimVirtualBus(channel, **kwargs)
    return can.Bus(interface=interface, channel=channel, **kwargs)


@dataclass
class PortStats:
    sent: int = 0
    received: int = 0
    dropped_tx: int = 0  # lost, unplugged or bus-off
    discarded_rx: int = 0  # arrived while unplugged or bus-off


class CanPort:
    def __init__(self, bus: can.BusABC, conditions: BusConditions | None = None, name: str = "") -> None:
        self.bus = bus
        self.conditions = conditions or BusConditions()
        self.name = name
        self.connected = True
        self.bus_off = False
        self.loss = 0.0
        self.delay = 0.0
        self.stats = PortStats()
        self._pending: deque[tuple[float, can.Message]] = deque()
        self._sim = bus if isinstance(bus, SimVirtualBus) else None  # its cheap drain

    @property
    def attached(self) -> bool:
        return self.connected and not self.bus_off

    def send(self, frame: can.Message, now: float) -> bool:
        """Put a frame on the bus (or into the delay line); False when it is lost."""
        if self._pending:
            self._flush(now)
        if not self.connected or self.bus_off:
            self.stats.dropped_tx += 1
            return False
        cond = self.conditions
        loss = self.loss + cond.loss
        if loss > 0.0 and cond.rng.random() < loss:
            self.stats.dropped_tx += 1
            return False
        delay = self.delay + cond.delay
        if delay > 0.0:
            self._pending.append((now + delay, frame))
            return True
        self._transmit(frame, now)
        return True

    def poll(self, now: float) -> list[can.Message]:
        """Every frame that arrived since the last poll (none while unplugged or bus-off)."""
        if self._pending:
            self._flush(now)
        if self._sim is not None:
            out = self._sim.drain()
            if not out:
                return out
        else:
            out = []
            recv = self.bus.recv
            while (frame := recv(timeout=0)) is not None:
                out.append(frame)
        if not self.connected or self.bus_off:
            self.stats.discarded_rx += len(out)
            return []
        self.stats.received += len(out)
        return out

    def accept(self, ids: set[int] | frozenset[int]) -> None:
        """Receive only frames with these standard identifiers (a hardware acceptance filter)."""
        if self._sim is not None:
            self._sim.accept(frozenset(ids))

    def close(self) -> None:
        self.bus.shutdown()

    def _flush(self, now: float) -> None:
        pending = self._pending
        while pending and pending[0][0] <= now + 1e-9:  # due times are sums of floats
            _, frame = pending.popleft()
            if self.attached:
                self._transmit(frame, now)
            else:
                self.stats.dropped_tx += 1

    def _transmit(self, frame: can.Message, now: float) -> None:
        frame.timestamp = now
        try:
            self.bus.send(frame, timeout=0)
        except can.CanError:
            self.stats.dropped_tx += 1
            return
        self.stats.sent += 1
