"""The oracle of one finished unit, and what it takes to believe it: no sockets, no clock.

Rules:
- Every lane unit opens with an answered request, the *lead*. Any byte back means the target took the connection
  (admitted); a connection refused, closed or reset without a byte back, or left unanswered, was never served:
  the target turned the newcomer away, left it in its listen backlog behind another client, or is gone. That
  is ``NOT_ADMITTED``, never a finding by itself: the unit runs again once the port is free (``pltf.fuzz.gate``)
  and only a target that no port answers any more is dead or hung (``Liveness``).
- After admission: a reply that does not decode strictly or answers the wrong request is ``bad-reply``; no close
  and no reply owed within the deadline ``timed-out`` (a stall when another connection is still served, a hang
  when none is); fewer replies than owed ``dropped`` (erratum E-WIRE-006: only malformed input closes a
  connection). A reply cut short by a close on malformed input with our bytes unread is ``CUT``: counted, not a
  suspicion (the close is right; the loss is TCP's).
- A suspicion is a finding only when it happens again: its unit replayed alone on a fresh connection once the
  port is free, ``REPLAYS`` times at most, must fail the same way ``NEEDED`` times (``confirm``). Otherwise it is
  reported apart as unconfirmed and never counts in the exit status.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from pltf.fuzz.target import CUT, Outcome

OK, NOT_ADMITTED = "ok", "not-admitted"
BAD_REPLY, TIMED_OUT, DROPPED = "bad-reply", "timed-out", "dropped"
SUSPICIONS = (BAD_REPLY, TIMED_OUT, DROPPED)
REPLAYS = 3  # replays of a suspicion's unit at most
NEEDED = 2  # of them that must fail the same way
STALL_PATIENCE = 3  # a stall is replayed with this many times the deadline: a slow target is not a stalled one

DROPPED_REASON = (
    "the target closed the connection before answering, after frames the strict codec accepts "
    "(erratum E-WIRE-006: only malformed input closes a connection): an internal error?"
)
TIMED_OUT_REASON = "the connection neither answered nor closed after our end-of-stream"
HOW = {  # how a connection that was not admitted ended
    "refused": "connection refused",
    "closed": "closed or reset before a byte came back",
    "timed-out": "accepted but never answered (a listen backlog, or a target that stopped)",
}


@dataclass(frozen=True)
class Verdict:
    kind: str  # OK, NOT_ADMITTED or one of SUSPICIONS
    reason: str = ""
    how: str = ""  # NOT_ADMITTED: refused | closed | timed-out
    cut: bool = False  # OK, but a reply was cut short by the close on a malformed case

    @property
    def suspicious(self) -> bool:
        return self.kind in SUSPICIONS


def admitted(out: Outcome) -> bool:
    """Whether the target served the connection: anything at all came back."""
    return out.got > 0 or bool(out.replies)


def judge(out: Outcome, owed: int, led: bool, keep: bool) -> Verdict:
    """The verdict of a finished unit. ``owed``: the replies the target must send (E-WIRE-006); ``led``: the
    session opened with the lead; ``keep``: every case of the unit is accepted by the strict codec."""
    return judge_counts(out.refused, out.got, out.timed_out, out.bad_reply, len(out.replies), owed, led, keep)


def judge_counts(
    refused: bool, got: int, timed_out: bool, bad_reply: str | None, replies: int, owed: int, led: bool, keep: bool
) -> Verdict:
    """``judge`` from what a connection counted (``got``: bytes back, ``replies``: replies decoded), without an
    ``Outcome`` (``pltf.fuzz.single.Single``)."""
    if refused:
        return _TURNED_AWAY["refused"]
    if led and not (got > 0 or replies):
        return _TURNED_AWAY["timed-out" if timed_out else "closed"]
    if bad_reply is not None:
        if not keep and bad_reply.startswith(CUT):
            return _CUT
        return Verdict(BAD_REPLY, bad_reply)
    if timed_out:
        return Verdict(TIMED_OUT, TIMED_OUT_REASON)
    if replies < owed:
        return Verdict(DROPPED, DROPPED_REASON)
    return _OK  # the verdict of most units: one object (verdicts are frozen)


_OK = Verdict(OK)
_CUT = Verdict(OK, cut=True)
_TURNED_AWAY = {how: Verdict(NOT_ADMITTED, HOW[how], how) for how in HOW}


def patient(deadline: float) -> float:
    """The reply deadline of a replay that judges a stall (the campaign's, and on a fresh instance): a target on a
    loaded machine that answers within it is slow, not stalled."""
    return deadline * STALL_PATIENCE


def confirm(kind: str, replay: Callable[[], str | None], replays: int = REPLAYS, needed: int = NEEDED) -> list[str]:
    """Replay a suspicion of ``kind`` until ``needed`` replays failed the same way or that can no longer happen;
    the kinds the replays showed (``ok`` for a clean one). ``replay`` returns the suspicion kind it saw, ``ok``, or
    None when the replay could not run (the target no longer admits us: the caller looks at liveness)."""
    seen: list[str] = []
    for _ in range(replays):
        got = replay()
        if got is None:
            break
        seen.append(got)
        same = seen.count(kind)
        if same >= needed or same + (replays - len(seen)) < needed:
            break
    return seen


def confirmed(kind: str, seen: list[str], needed: int = NEEDED) -> bool:
    return seen.count(kind) >= needed


class Liveness:
    """When no port has admitted us for ``patience`` seconds while we kept trying, the target is gone: dead when
    the last attempts were refused or closed, hung when they were accepted and never answered. When one port
    has not admitted us for that long while another has, that port is stuck."""

    def __init__(self, ports: int, patience: float, now: float) -> None:
        self.patience = patience
        self.last_admitted = now
        self.failing: dict[int, str] = {}  # port index -> how its latest attempt ended, while not admitted
        self.failing_since: dict[int, float] = {}
        self.ports = ports

    def admitted(self, port: int, now: float) -> None:
        self.last_admitted = now
        self.failing.pop(port, None)
        self.failing_since.pop(port, None)

    def turned_away(self, port: int, how: str, now: float) -> None:
        self.failing[port] = "refused" if self.failing.get(port) == "refused" else how  # refused once: gone
        self.failing_since.setdefault(port, now)

    def stuck(self, now: float) -> int | None:
        """A port that has not admitted us for ``patience`` while another one has meanwhile."""
        for port, since in sorted(self.failing_since.items()):
            if now - since >= self.patience and self.last_admitted > since:
                return port
        return None

    def silent_for(self, now: float) -> float:
        return now - self.last_admitted

    def verdict(self, now: float) -> str | None:
        """``dead`` (connections refused), ``hang`` (accepted, never answered), ``deaf`` (closed unanswered) or
        None (alive, or not yet long enough to tell)."""
        if len(self.failing) < self.ports or now - self.last_admitted < self.patience:
            return None
        hows = set(self.failing.values())
        return "dead" if "refused" in hows else "hang" if hows == {"timed-out"} else "deaf"
