"""The target side of a run: its configuration, the statuses it reports, its persistent sessions.

Rules:
- ``Target`` lives for the whole run: the configuration, the coverage recorder and one persistent session per
  port (guide 6.1: one client per port, so the suite holds at most one connection per port unless a case tests
  exactly that). What one case works with is ``context.CaseContext``.
- A new connection is probed with CMD_GET_STATUS and retried for ``connect_window`` seconds: the target may
  not yet have noticed that our previous client on that port is gone (one client per port). A refused connect is
  retried too once the run has been served, for ``RESTART_WINDOW`` s (a restart: the port is gone while the
  program starts again, erratum E-BEH-007, zoo matrix row 10); served again, ``Target.restarts`` counts it, a run
  note names the case in flight (``Target.case``) and how long the port refused, and the runner runs that case
  again. A port that still refuses at the end of the window is named so: "refused connections for N s after it
  had served this run" (a restart that did not come back, or a crash).
- The last status read stands for the current one while nothing was sent, connected or closed since
  (``wire.Session.events``) and it is under ``STATUS_FRESH`` wall s old - across cases too, and a probe's reply
  counts: each round trip counts against a slow link (issue 17).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from pltf.conformance_tests.catalogue import Tier
from pltf.conformance_tests.coverage import Coverage
from pltf.conformance_tests.outcome import Fail, TargetFailure, Unreachable
from pltf.conformance_tests.wire import CaseBudget, Session, WireLog
from pltf.spec.codec import build
from pltf.spec.model import enum_classes
from pltf.spec.telegram import Telegram

STATUS_FRESH = 0.5  # wall s a status read stands for the current one when nothing was sent since
RESTART_WINDOW = 15.0  # wall s a refused port of a target served before is waited for (a restart, E-BEH-007)
# The spec's enums are built at import; mypy sees them as plain IntEnum classes without members.
MotionMode: Any = enum_classes()["MotionMode"]
OperationState: Any = enum_classes()["OperationState"]


@dataclass
class Config:
    host: str
    port: int
    second_port: int | None = None
    time_scale: float = 1.0
    profile: str = "strict"  # or "original"
    tier: Tier = Tier.STANDARD
    keyword: str | None = None
    allow_motion: bool = False
    simulator: bool = False  # the user declares the target a simulator: motion and outputs are allowed
    allow_shutdown: bool = False  # CMD_EXIT / CMD_SHUTDOWN_HOST may be sent (the target stops)
    reruns: int = 2
    reply_timeout: float = 3.0  # wall seconds for one reply
    connect_window: float = 5.0  # wall seconds to get a port back after our previous client left
    min_wall: float = 0.25  # wall floor of every wait derived from simulated time
    probe_timeout: float = 1.0  # wall seconds for the GET_STATUS that probes a new connection
    case_budget: float | None = None  # wall seconds one case may take (None: pace.case_budget)
    run_budget: float | None = None  # wall seconds the whole run may take (None: no limit)
    reply_time: float | None = None  # the target's GET_STATUS round trip measured at the start (pace.measure)
    setup_time: float = 0.0  # wall s a new connection is answered after its connect, beyond a reply (pace.measure)
    pipeline: bool = False  # the target answers pipelined requests in order (pace.measure, erratum E-WIRE-008)
    greeting: bool = False  # every connection sends CMD_CONNECT_TO_PLTF first (pace.measure, erratum E-BEH-006)

    @property
    def motion_allowed(self) -> bool:
        return self.allow_motion or self.simulator


def greet(s: Session, config: Config) -> Session:
    """``s``, its first telegram CMD_CONNECT_TO_PLTF where the target answers nothing on a connection before it
    (``Config.greeting``, erratum E-BEH-006; on a platform already connected it changes nothing, guide 4.2)."""
    if config.greeting:
        s.send(build("request", "CMD_CONNECT_TO_PLTF"))
    return s


@dataclass(frozen=True)
class Status:
    """The part of CMD_GET_STATUS the chart cares about."""

    op: int
    initialized: int
    mode: int
    telegram: Telegram

    @classmethod
    def of(cls, t: Telegram) -> Status:
        return cls(t.operation_state, t.initialized, t.motion_mode, t)  # type: ignore[attr-defined]

    def describe(self) -> str:
        op = OperationState(self.op).name if self.op in OperationState._value2member_map_ else self.op
        mode = MotionMode(self.mode).name if self.mode in MotionMode._value2member_map_ else self.mode
        return f"{op}, initialized {self.initialized}, {mode}"


class Target:
    """Run-wide state: configuration, coverage and the persistent sessions."""

    def __init__(self, config: Config, coverage: Coverage | None = None) -> None:
        self.config = config
        self.coverage = coverage or Coverage()
        self._sessions: dict[str, Session] = {}
        self.budget = CaseBudget()  # the running case's (pace.py); every session of the run carries it
        self.last_status: tuple[int, float, Status] | None = None  # (Session.events, when, status) of the last read
        self.prompt = True  # every commanded state showed at the first status after the command (see the rules)
        self.notes: list[str] = []  # about the run as a whole
        self.reached = False  # a connection was served in this run: a refused connect since is waited out
        self.restarts = 0  # times the target restarted (a port refused connections, then served again: E-BEH-007)
        self.restart_seen = ""  # how the last restart showed
        self.restart_cases: list[str] = []  # the case in flight at each restart (run notes, the run's summary)
        self.case = ""  # the case in flight (set by the runner; named in the notes)

    def record(self, reply: Telegram) -> Status:
        """A CMD_GET_STATUS reply just read, nothing asked after it: the current status until something moves."""
        status = Status.of(reply)
        self.last_status = (Session.events, time.monotonic(), status)
        return status

    def fresh_status(self) -> Status | None:
        last = self.last_status
        if last is not None and last[0] == Session.events and time.monotonic() - last[1] < STATUS_FRESH:
            return last[2]
        return None

    def port_of(self, label: str) -> int:
        if label.startswith("B"):
            if self.config.second_port is None:
                raise Fail("no --second-port given")
            return self.config.second_port
        return self.config.port

    def connect(
        self,
        label: str,
        log: WireLog,
        observer: Any,
        *,
        probe: bool = True,
        window: float | None = None,
        probe_timeout: float | None = None,
    ) -> Session:
        """A new session on the port of ``label``, probed with GET_STATUS and retried (see the module rules)."""
        cfg = self.config
        waits_restart = window is None  # a refused port of a target served before: waited out (RESTART_WINDOW)
        window = cfg.connect_window if window is None else window
        began = time.monotonic()
        deadline = began + window
        delay, last, refused = 0.01, "no attempt", None  # refused: when the first connect was refused
        while True:
            s = Session(
                cfg.host,
                self.port_of(label),
                label=label,
                log=log,
                timeout=cfg.reply_timeout,
                observer=observer,
                profile=cfg.profile,
                budget=self.budget,
            )
            try:
                greet(s.connect(), cfg)
                if probe:
                    self.record(
                        s.request(
                            build("request", "CMD_GET_STATUS"),
                            timeout=probe_timeout or min(cfg.reply_timeout, cfg.probe_timeout),
                        )
                    )
                self._served(label, refused)
                return s
            except Unreachable as exc:
                s.close()
                if "refused" in str(exc).lower() and not self.reached:
                    raise  # nothing listens: a busy port accepts and closes, it does not refuse
                if refused is None and "refused" in str(exc).lower():  # gone since: a restart, or a crash
                    refused = time.monotonic()
                if refused is not None and waits_restart:
                    deadline = max(deadline, began + RESTART_WINDOW)
                last = str(exc)
            except TargetFailure as exc:
                last = str(exc).removeprefix(f"port {label} ({cfg.host}:{self.port_of(label)}): ")
                s.close()
            except BaseException:  # anything else ends the run's connect: the socket is not left to the collector
                s.close()
                raise
            if time.monotonic() + delay > deadline:
                raise Unreachable(self._gone(label, window, refused if waits_restart else None, last))
            self.budget.check()
            time.sleep(delay)
            delay = min(delay * 2, 0.2)

    def _gone(self, label: str, window: float, refused: float | None, last: str) -> str:
        """Why no connection came: a port refused since it had served this run says so, with how long."""
        where = f"port {label} ({self.config.host}:{self.port_of(label)})"
        if refused is None:
            return f"{where}: no working connection within {window:.0f} s: {last}"
        return (
            f"{where}: refused connections for {time.monotonic() - refused:.1f} s after it had served this run (a "
            f"restart that did not come back within {RESTART_WINDOW:g} s, erratum E-BEH-007, or a crash): {last}"
        )

    def _served(self, label: str, refused: float | None) -> None:
        """A connection was served; one refused before it means the target restarted (erratum E-BEH-007)."""
        self.reached = True
        if refused is not None:
            self.restarted(
                f"port {label} refused connections for {time.monotonic() - refused:.1f} s, then served again"
            )

    def restarted(self, seen: str) -> None:
        """The target restarted (``seen`` says how it showed): counted and noted; the runner runs the case again."""
        self.restarts, self.restart_seen = self.restarts + 1, seen
        self.restart_cases.append(self.case)
        during = f" during {self.case}" if self.case else ""
        self.notes.append(
            f"{seen}{during}: the target restarted (erratum E-BEH-007, an alternative reading; zoo behaviour matrix "
            "row 10); the case in flight is run again"
        )

    def session(self, label: str, log: WireLog, observer: Any) -> Session:
        s = self._sessions.get(label)
        if s is None or not s.is_open:
            if s is not None:
                s.close()
            s = self._sessions[label] = self.connect(label, log, observer)
        s.log, s.observer = log, observer
        return s

    def drop(self, label: str) -> None:
        s = self._sessions.pop(label, None)
        if s is not None:
            s.close()

    def close(self) -> None:
        for label in list(self._sessions):
            self.drop(label)
