"""What the controller hands back: events, connect/init transactions, self-test results, buffered CAN frames.

Plain data; the controller (``pltf.fake_hardware.controller``) creates and updates them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal, NamedTuple

from pltf.fake_hardware.candb import Node, St


class HwEvent(NamedTuple):
    kind: str  # emergency_pressed/_released, node_lost/_back, bus_off/_on, frames_lost, connect_done, init_done
    node: Node | None
    text: str

    def __str__(self) -> str:
        return self.text


class SelfTestResult(NamedTuple):
    node: Node
    passed: bool
    errors: int  # board specific error bits; 0xFFFF: no answer
    status: int


@dataclass
class Transaction:
    kind: Literal["connect", "init"]
    started: float
    deadline: float
    sequence: int
    pending: set[Node]
    answers: dict[Node, dict[str, Any]] = field(default_factory=dict)
    finished_at: float | None = None

    @property
    def done(self) -> bool:
        return self.finished_at is not None

    @property
    def missing(self) -> tuple[Node, ...]:
        """Nodes that did not answer (final once ``done``)."""
        return tuple(sorted(self.pending))

    @property
    def results(self) -> dict[Node, SelfTestResult]:
        """Self-test results of an init transaction, a node without answer as failed with errors 0xFFFF."""
        if self.kind != "init":
            return {}
        out = {
            n: SelfTestResult(n, bool(a["Passed"]), int(a["Errors"]), int(a["Status"])) for n, a in self.answers.items()
        }
        out.update({n: SelfTestResult(n, False, 0xFFFF, St.ABSENT) for n in self.pending})
        return dict(sorted(out.items()))

    @property
    def ok(self) -> bool:
        """Done, every node answered, and (init) every self test passed."""
        return self.done and not self.pending and all(r.passed for r in self.results.values())


class CanRecord(NamedTuple):
    """One frame of CMD_GET_CAN_MESSAGES: simulated seconds, 11-bit id, 8 data bytes (zero padded, E-REP-001)."""

    timestamp: float
    can_id: int
    data: bytes


class ControllerError(Exception):
    """A command the controller cannot carry out in its present state (bus down, wrong node, bad channel)."""
