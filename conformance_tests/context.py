"""What a case works with: the target's sessions, simulated time, the known state, and clean-up.

Rules:
- ``CaseContext`` lives for one case: its wire log, its deviations and notes, and the finalizers that restore
  what it changed (parameters, pose, documents, outputs), run even when it fails. It works through the run's
  ``target.Target`` (the configuration, the coverage recorder, the persistent sessions, the connection probe
  and the status freshness rules: target.py).
- Time: every duration a case names is simulated seconds (the target's clock); ``wall`` converts with the
  declared ``--time-scale``, never below a floor that absorbs the scheduling noise of a loaded machine.
- The known state: ``ensure(state, mode)`` drives the target there through the chart (chart.PATH_FROM_READY)
  and checks it through CMD_GET_STATUS; when it cannot, the case fails as a precondition failure.
- Pipelining (erratum E-WIRE-008; only when ``Config.pipeline``: the target answered pipelined requests in order
  at the start of the run): ``enter`` sends the way to a state - each leg followed by the CMD_GET_STATUS that
  checks it - and what the case sends in that state in one write, and judges the statuses in order. The way is
  taken for granted only while the target has shown every commanded state at the first status after the
  command (``Target.prompt``); a status that shows another state ends that for the run, and the step is done
  again one request at a time, as without pipelining (what the case sent meanwhile was sent in vain).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any, TypeVar

from pltf.conformance_tests import chart, reported
from pltf.conformance_tests.catalogue import Case
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.outcome import ConnectionClosed, Deviation, Fail, NoConnection, TargetFailure, Unreachable
from pltf.conformance_tests.target import Config, MotionMode, OperationState, Status, Target, greet
from pltf.conformance_tests.wire import Pause, Session, WireLog, answered
from pltf.spec.codec import build
from pltf.spec.telegram import Telegram

T = TypeVar("T")
Then = Callable[[], list[Telegram]]  # the replies to what a case sends once in a state (CaseContext.enter)
PACED = 0.8  # simulated s: a target whose reply takes longer is sampled at the platform's pace (link_paced)
# (at 0.25 a loaded reference server behind a fast link was paced and failed a program case; at 0.8 the slow link
# at time scale 5 - 126 ms replies, 0.63 simulated s - is polled reply by reply and its watchdog and program-stop
# cases can come out INCONCLUSIVE: a slow link is told from a loaded server by its reply time alone, zoo/README)


@dataclass(frozen=True)
class Leg:
    """One leg of the way to a state: the commands, the operation state and motion mode the status must show
    after them, and the way to take the leg one request at a time (polling, failing as a precondition)."""

    commands: tuple[Telegram, ...]
    op: int
    mode: int
    run: Callable[[Status], Status]  # from the status before the leg
    foreseen: bool = True  # False: needed only if the leg before it changed the mode (not sent when pipelined)


@dataclass
class CaseContext:
    target: Target
    case: Case
    log: WireLog = field(default_factory=WireLog)
    deviations: list[Deviation] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    unsolicited: list[tuple[str, bytes]] = field(default_factory=list)
    abuse_from: Status | None = None  # the status just before a case sent malformed input
    sent: set[str] = field(default_factory=set)  # the names of the telegrams the case sent (a restart's judge)
    _finalizers: list[tuple[str, Callable[[], object]]] = field(default_factory=list)
    _extra: list[Session] = field(default_factory=list)

    # ---- observer hooks (wire.Observer)
    def on_sent(self, telegram: Telegram) -> None:
        self.target.coverage.sent(telegram)
        self.sent.add(telegram.NAME)

    def on_received(self, telegram: Telegram) -> None:
        self.target.coverage.received(telegram)

    def on_deviation(self, deviation: Deviation) -> None:
        if deviation not in self.deviations:
            self.deviations.append(deviation)

    def on_unsolicited(self, port: str, data: bytes) -> None:
        self.unsolicited.append((port, data))

    # ---- configuration
    @property
    def config(self) -> Config:
        return self.target.config

    @property
    def profile(self) -> str:
        return self.config.profile

    def wall(self, sim_seconds: float) -> float:
        return max(self.config.min_wall, sim_seconds / self.config.time_scale)

    def newcomer_wait(self, sim_seconds: float) -> float:
        """Wall seconds to wait for what a new connection meets (served, turned away, closed): ``wall(sim_seconds)``
        plus the connection's measured set-up (pace.py: a timer-driven accept serves a newcomer up to a tick after
        its connect, issue 32)."""
        return self.wall(sim_seconds) + self.config.setup_time

    def close_wait(self, sim_seconds: float) -> float:
        """Wall seconds to wait for a close a case requires: ``wall(sim_seconds)``, never under the reply timeout.
        A close is the target's answer and travels like one (through a relay, on a loaded machine); waiting costs
        nothing on a target that closes, so a required close gets a reply's patience (issue 17: CMD_CLOSE_SOCKET
        through the slow-release relay at load 8 closed after 0.4 s, the 0.25 s wait had ended)."""
        return max(self.wall(sim_seconds), self.config.reply_timeout)

    def sleep(self, sim_seconds: float) -> None:
        time.sleep(sim_seconds / self.config.time_scale)

    # ---- outcomes
    def deviate(self, erratum: str, reading: int | None, detail: str) -> None:
        self.on_deviation(Deviation(erratum, reading, detail))

    def note(self, text: str) -> None:
        self.notes.append(text)

    def on_exit(self, what: str, fn: Callable[[], object]) -> None:
        """Call ``fn`` when the case ends (last registered first); what it returns is dropped."""
        self._finalizers.append((what, fn))

    def finish(self) -> None:
        """Run the finalizers (last registered first) and close the case's extra sessions."""
        while self._finalizers:
            what, fn = self._finalizers.pop()
            try:
                fn()
            except Exception as exc:
                self.note(f"clean-up '{what}' failed: {exc}")
        for s in self._extra:
            s.close()
        self._extra.clear()

    # ---- sessions
    def session(self, label: str = "A") -> Session:
        try:
            return self.target.session(label, self.log, self)
        except Unreachable as exc:
            raise NoConnection(f"target unreachable: {exc}") from None

    def fresh(self, label: str = "A", *, probe: bool = True) -> Session:
        """A new connection of our own on the port of ``label``; the persistent one there is closed first."""
        self.target.drop(label[:1])
        try:
            s = self.target.connect(label, self.log, self, probe=probe)
        except Unreachable as exc:
            raise NoConnection(f"target unreachable: {exc}") from None
        self._extra.append(s)
        return s

    def extra(self, label: str) -> Session:
        """An additional raw connection (no probe, no retry) - e.g. a second client on a busy port."""
        s = Session(
            self.config.host,
            self.target.port_of(label),
            label=label,
            log=self.log,
            timeout=self.config.reply_timeout,
            observer=self,
            profile=self.profile,
            budget=self.target.budget,
        )
        try:
            greet(s.connect(), self.config)
        except Unreachable as exc:
            raise ConnectionClosed(str(exc)) from None
        except TargetFailure:  # the greeting could not be sent: the newcomer was closed at once
            s.eof = True
        self._extra.append(s)
        return s

    def before_abuse(self) -> Status:
        """Record the state the abuse must not change (the runner compares it after the case): the status, read
        now unless one was read a moment ago with nothing sent since."""
        self.abuse_from = self.current_status()
        return self.abuse_from

    def reset_session(self, label: str = "A") -> None:
        self.target.drop(label)

    # ---- telegrams
    def send(self, telegram: str, /, label: str = "A", **fields: Any) -> None:
        """Send request ``telegram`` (by name) with ``fields`` on the session of ``label``."""
        self.session(label).send(build("request", telegram, **fields))

    def get(self, telegram: str, /, label: str = "A", **fields: Any) -> Telegram:
        """Send GET_* request ``telegram`` and return its reply (decoded strictly)."""
        return self.session(label).request(build("request", telegram, **fields))

    def status(self, label: str = "A") -> Status:
        return self.target.record(self.get("CMD_GET_STATUS", label))

    def current_status(self) -> Status:
        """The status: the last one read when nothing was sent, connected or closed since and it is under
        ``STATUS_FRESH`` wall s old (each round trip counts against a slow link: issue 17), else a new GET_STATUS."""
        return self.target.fresh_status() or self.status()

    def exchange(self, items: Sequence[Telegram | Pause], label: str = "A") -> list[Telegram]:
        """Send ``items`` and return the replies of the answered ones in order: in one write when the target takes
        pipelined requests (erratum E-WIRE-008), else one request at a time, each reply read before the next is
        sent. A CMD_GET_STATUS asked last is the current status (``Target.record``)."""
        s = self.session(label)
        if self.config.pipeline:
            replies = s.exchange(items)
        else:
            replies = []
            for item in items:
                replies += s.exchange([item])
        if items and not isinstance(items[-1], Pause) and items[-1].NAME == "CMD_GET_STATUS":
            self.target.record(replies[-1])
        return replies

    def position(self, label: str = "A") -> Telegram:
        """CMD_GET_POSITION, its pose and velocities plausible (reported.py: else the case FAILs naming them)."""
        return reported.position(self.get("CMD_GET_POSITION", label))

    def quiet(self, sim_seconds: float = 0.3, label: str = "A") -> None:
        """Fail when the target sends anything unasked within the time (guide 6.1, erratum E-CMD-013)."""
        got = self.session(label).silence(self.wall(sim_seconds))
        if got:
            raise Fail(f"the target sent {len(got)} bytes nobody asked for: {got[:24].hex()}", erratum="E-CMD-013")

    def poll(self, fn: Callable[[], T], until: Callable[[T], bool], within: float, every: float = 0.05) -> T:
        """Call ``fn`` until ``until(result)`` or ``within`` simulated seconds passed; the last result."""
        deadline = time.monotonic() + self.wall(within)
        while True:
            value = fn()
            if until(value) or time.monotonic() >= deadline:
                return value
            time.sleep(max(0.002, every / self.config.time_scale))

    def link_paced(self, gap: float = PACED) -> bool:
        """Whether polling one request at a time would sample the target less often than every ``gap`` simulated
        s (its measured reply time is longer) while it takes pipelined requests (E-WIRE-008): then a case samples
        at the platform's pace instead (``timeline``; a slow link, issue 17). A fast target is polled as before: a
        stream of unpaced requests can starve a loaded simulator (poses.hold)."""
        reply = self.config.reply_time or 0.0
        return self.config.pipeline and reply * self.config.time_scale > gap

    def timeline(
        self, ask: Telegram, seconds: float, events: Sequence[tuple[float, Telegram]], period: float = 0.1
    ) -> list[tuple[float, Telegram]]:
        """Send each of ``events`` at its simulated time (s from now), and ``ask`` every ``period`` simulated s for
        ``seconds``, none waiting for a reply (pipelined, erratum E-WIRE-008); the replies to ``ask``, each with
        the simulated time it was asked at. What a reply shows is the platform's at that time, whatever the link
        then takes to bring it."""
        session, scale = self.session(), self.config.time_scale
        due, asked = sorted(events, key=lambda e: e[0]), []
        t0 = time.monotonic()
        while True:
            t = (time.monotonic() - t0) * scale
            while due and due[0][0] <= t:
                session.send(due.pop(0)[1])
            if t > seconds and not due:
                break
            session.send_pipelined([ask])
            asked.append(t)
            # the next ask at its own time from the start (a sleep that overran on a loaded machine is not added on)
            time.sleep(max(0.0, t0 + len(asked) * period / scale - time.monotonic()))
        return [(t, session.next_reply()) for t in asked]

    def settle_time(self) -> float:
        """Wall s a command that should have no effect gets to show one before the status that judges it."""
        return max(0.02, 0.3 / self.config.time_scale)

    def settle(self) -> None:
        """Let a command that should have no effect have its chance to show one."""
        time.sleep(self.settle_time())

    # ---- the known state
    def ensure(self, state: St, mode: int = MotionMode.MODE_MOTION_NO) -> Status:
        """Drive the target to ``state`` with motion mode ``mode`` (set in Ready); precondition failure if not."""
        return self.enter(state, mode)[0]

    def enter(
        self, state: St, mode: int = MotionMode.MODE_MOTION_NO, then: Sequence[Telegram | Pause] = ()
    ) -> tuple[Status, Then]:
        """``ensure(state, mode)``, then ``then`` in that state: the status there, and a function that returns the
        replies to the answered requests of ``then`` in order (call it once, where the case sent ``then`` before:
        what the target does to them is raised there). Pipelined when the target allows it (module rules)."""
        s = self.current_status()
        legs = self._legs(s, state, mode)
        foreseen = [leg for leg in legs if leg.foreseen]
        if foreseen and self.config.pipeline and self.target.prompt:
            done = self._pipelined(foreseen, then)
            if done is not None:
                return done
            s = self.status()
            legs = self._legs(s, state, mode)
        for leg in legs:
            s = leg.run(s)
        return s, lambda: self.exchange(then)

    def _legs(self, s: Status, state: St, mode: int) -> list[Leg]:
        """The way from ``s`` to ``state`` and ``mode``, leg by leg (guide 4.2, chart.PATH_FROM_READY)."""
        if (s.op, s.mode, state) == (OperationState.ST_OP_RUNNING, mode, St.BREAKED):  # one step: guide 6.3 BREAK
            return [self._leg(("CMD_BREAK",), OperationState.ST_OP_BREAKED, mode)]
        legs = []
        if s.op in (OperationState.ST_OP_RUNNING, OperationState.ST_OP_BREAKED):
            legs.append(self._leg(("CMD_STOP",), OperationState.ST_OP_READY, s.mode))
        elif s.op == OperationState.ST_OP_NOT_INITIALIZED:
            init = tuple(build("request", c) for c in ("CMD_CONNECT_TO_PLTF", "CMD_INIT_PLTF"))
            legs.append(Leg(init, OperationState.ST_OP_READY, s.mode, lambda _: self._initialize()))
        if legs or s.mode != mode:  # the mode is set in Ready (guide 6.3 CMD_SET_MODE) when it is not the one asked
            set_mode = (build("request", "CMD_SET_MODE", mode=mode),)
            legs.append(Leg(set_mode, OperationState.ST_OP_READY, mode, self._mode_run(mode), s.mode != mode))
        path = chart.PATH_FROM_READY[state]
        if path:
            legs.append(self._leg(path, chart.REPORTED[state], mode))
        return legs

    def _leg(self, commands: tuple[str, ...], op: int, mode: int) -> Leg:
        def run(_: Status) -> Status:
            for c in commands:
                self.send(c)
            return self._await_op(op, " + ".join(commands), within=10.0)

        return Leg(tuple(build("request", c) for c in commands), op, mode, run)

    def _mode_run(self, mode: int) -> Callable[[Status], Status]:
        def run(before: Status) -> Status:
            if before.mode == mode:
                return before
            self.send("CMD_SET_MODE", mode=mode)
            s = self.poll(self.status, lambda x: x.mode == mode, within=5.0)
            if s.mode != mode:
                raise Fail(
                    f"precondition: CMD_SET_MODE({MotionMode(mode).name}) in Ready left {s.describe()}",
                    precondition=True,
                )
            return s

        return run

    def _pipelined(self, legs: list[Leg], then: Sequence[Telegram | Pause]) -> tuple[Status, Then] | None:
        """Every leg with its CMD_GET_STATUS, then ``then``, in one write; None when a status shows that the way was
        not taken as foreseen (then nothing of it is judged: the caller goes again one request at a time)."""
        ask = build("request", "CMD_GET_STATUS")
        session = self.session()
        session.send_pipelined([*(t for leg in legs for t in (*leg.commands, ask)), *then])
        last = None
        for leg in legs:
            last = Status.of(session.next_reply())
            if last.op != leg.op:
                self.target.prompt = False
                why = (
                    f"the target showed {last.describe()} at the first status after "
                    f"{' + '.join(t.NAME for t in leg.commands)} ({self.case.id}): the way to a state is taken "
                    "one leg at a time from here"
                )
                self.note(why)
                self.target.notes.append(why)
                self._abandon(session)
                return None
            if last.mode != leg.mode:
                self._abandon(session)  # the mode was foreseen wrong (changed by STOP or INIT?)
                return None
        assert last is not None
        if not then:
            self.target.record(last.telegram)
        return last, lambda: self._rest(session, then)

    def _abandon(self, session: Session) -> None:
        """The replies still due on ``session`` are read and dropped (the connection is dropped if that fails)."""
        try:
            session.exchange([])
        except TargetFailure:
            self.target.drop(session.label)

    def _rest(self, session: Session, then: Sequence[Telegram | Pause]) -> list[Telegram]:
        replies = [session.next_reply() for item in then if not isinstance(item, Pause) and answered(item.NAME)]
        if then and not isinstance(then[-1], Pause) and then[-1].NAME == "CMD_GET_STATUS":
            self.target.record(replies[-1])
        return replies

    def _initialize(self) -> Status:
        """CONNECT + INIT. A self test may fail on a platform that still rolls or turns (a gyro calibrates at
        rest, erratum E-HW-019): the operator's remedy, a second CMD_INIT_PLTF a moment later, is tried once."""
        how = "CMD_CONNECT_TO_PLTF + CMD_INIT_PLTF"
        self.send("CMD_CONNECT_TO_PLTF")
        self.send("CMD_INIT_PLTF")
        s = self.poll(self.status, lambda x: x.op == OperationState.ST_OP_READY, within=15.0)
        if s.op == OperationState.ST_OP_READY:
            return s  # no second look: each round trip counts against a slow link
        self.sleep(1.0)
        self.send("CMD_CONNECT_TO_PLTF")  # refused when the bus is up already: changes nothing
        self.send("CMD_INIT_PLTF")
        how += " (twice)"
        return self._await_op(OperationState.ST_OP_READY, how, within=15.0)

    def _await_op(self, op: int, how: str, within: float) -> Status:
        s = self.poll(self.status, lambda x: x.op == op, within=within)
        if s.op != op:
            raise Fail(
                f"precondition: {how} did not bring the target to {OperationState(op).name} (status: {s.describe()})",
                precondition=True,
            )
        return s

    def ready(self, mode: int = MotionMode.MODE_MOTION_NO) -> Status:
        return self.ensure(St.READY, mode)

    # ---- restoring what a case changes
    def preserve_pose(self) -> Telegram:
        pos = self.position()

        def restore() -> None:
            self.send("CMD_SET_FRM_PLTF", x=pos.x, y=pos.y, angle=round(math.degrees(pos.angle) * 1000))  # type: ignore[attr-defined]

        self.on_exit("restore the estimated pose", restore)
        return pos

    def preserve_param(self, key: str) -> str:
        return self.preserve_params([key])[0]

    def preserve_params(self, keys: Sequence[str]) -> list[str]:
        """GET each parameter (pipelined, erratum E-WIRE-008); restore each with SET at the end. The values."""
        replies = self.exchange([build("request", "CMD_GET_PLTF_PARAM", key=key) for key in keys])
        values: list[str] = [r.value for r in replies]  # type: ignore[attr-defined]
        for key, value in zip(keys, values, strict=True):
            self.on_exit(f"restore parameter {key}", partial(self.send, "CMD_SET_PLTF_PARAM", key=key, value=value))
        return values

    def preserve_document(self, kind: str) -> tuple[str, str]:
        """GET the active map/roadmap/program; restore it with SET at the end. Returns (xml, name)."""
        reply = self.get(f"CMD_GET_{kind.upper()}")
        xml: str = reply.xml  # type: ignore[attr-defined]
        name: str = getattr(reply, "name", "")

        def restore() -> None:
            if not xml.strip():
                return  # nothing was active: nothing to restore
            if kind == "program":
                self.send("CMD_SET_PROGRAM", xml=xml)
            else:
                self.send(f"CMD_SET_{kind.upper()}", name=name, xml=xml)

        self.on_exit(f"restore the active {kind}", restore)
        return xml, name
