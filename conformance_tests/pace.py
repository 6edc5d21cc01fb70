"""A bounded run against any target: one early measurement of its reply time, budgets, and a watch that stops
waiting on a target that no longer answers (issue 17: against a slow or stuck target a standard run ends within
5 minutes, with verdicts that say why).

Rules:
- ``measure`` runs once, before the first case: CMD_GET_STATUS three times on a fresh connection to port A (a
  connection turned away is retried for the connect window), the first allowed ``PATIENCE`` s. Their median is
  the target's reply time (None when nothing came). Then three GET_* requests in one write: when their replies
  come in the order asked, the run pipelines its requests (``Config.pipeline``, erratum E-WIRE-008); when not,
  it sends one request at a time, as a client that waits for each reply.
- The connection's set-up is measured too (issue 32): how long after its connect a new connection's first request
  is answered, beyond a reply time - on that first connection and on a second one (the larger: a GUI
  application's timer-driven accept serves a newcomer up to a tick after it connects). ``Config.setup_time``.
- A target that answers nothing within ``PATIENCE`` is asked once more on a new connection: GET_STATUS,
  CMD_CONNECT_TO_PLTF, GET_STATUS in one write. When only the second GET_STATUS is answered, the target answers
  nothing on a connection before its CMD_CONNECT_TO_PLTF (erratum E-BEH-006, zoo matrix row 9): every connection
  of the run then sends CMD_CONNECT_TO_PLTF first (``Config.greeting``), and the run says so.
- ``apply`` scales the run's waits to it: a reply time up to ``MAX_SCALED`` raises the wall floor of every wait
  derived from simulated time (``Config.min_wall``) to ``WAIT_SCALE`` and the connection probe's patience to
  ``SCALE`` times the reply time (a wait floor of two reply times, not four: the standard tier has hundreds of
  such waits, and at four a slow link's run did not fit its budget), so a slow but conforming target (a slow
  link) is judged on what it does, not on how fast it does it. A slower target keeps the configured waits, and
  the run says at its start why its cases will fail. The connection probe's patience scales to the reply time
  plus the set-up, and so does every wait that spans a new connection (``CaseContext.newcomer_wait``).
- Budgets (wall seconds): a case's waits end at its budget, ``CASE_WALL + CASE_SIM / time scale`` unless given;
  the case is then INCONCLUSIVE "case budget spent" and not re-run. The run's budget (``Config.run_budget``) ends
  the run: the cases left are INCONCLUSIVE "not run"; a case begun late gets what is left of it (at least
  ``runner.LAST_CASE_GRACE``) and is not re-run.
- ``Watch``: after ``STUCK_AFTER`` cases in a row that ended with the target not answering at all (a reply
  timeout, no working connection, a spent budget), one health check - a new connection answered with
  CMD_GET_STATUS within the reply timeout. If it fails, the cases that follow are not run (INCONCLUSIVE, "the
  target stopped answering ...", naming the first silent case); a health check every ``RECHECK`` s lets them run
  again when the target answers again.
"""

from __future__ import annotations

import dataclasses
import statistics
import time
from dataclasses import dataclass, field

from pltf.conformance_tests.outcome import ConnectionClosed, TargetFailure, Unreachable
from pltf.conformance_tests.target import Config, Target, greet
from pltf.conformance_tests.wire import NullObserver, Session, WireLog
from pltf.spec.codec import build

PATIENCE = 15.0  # s the first GET_STATUS of the run may take
MAX_SCALED = 1.0  # s: a reply time up to this scales the waits; a slower target is not waited for
SCALE = 4.0  # the connection probe's patience scales to this many reply times
WAIT_SCALE = 2.0  # the wall floor of a wait derived from simulated time: this many reply times
CASE_WALL, CASE_SIM = 30.0, 240.0  # a case's budget: wall s + simulated s (at the declared time scale)
STUCK_AFTER = 3  # silent cases in a row before the health check
RECHECK = 20.0  # s between two health checks while the target stays silent


@dataclass(frozen=True)
class Pace:
    reply: float | None  # the median GET_STATUS round trip, s (None: no reply within PATIENCE)
    error: str = ""
    pipeline: str = ""  # "" when pipelined requests were answered in order, else why the run does not pipeline
    setup: float = 0.0  # s a new connection's first reply comes after its connect, beyond a reply time
    greeting: bool = False  # nothing is answered on a connection before its CMD_CONNECT_TO_PLTF (E-BEH-006)

    def describe(self, config: Config) -> str:
        if self.reply is None:
            return f"the target did not answer CMD_GET_STATUS within {PATIENCE:g} s at the start ({self.error})"
        text = f"the target answers CMD_GET_STATUS in {self.reply * 1000:.0f} ms"
        if self.reply > config.reply_timeout:
            text += (
                f", over the reply timeout of {config.reply_timeout:g} s (--reply-timeout): every case that "
                "reads the status will fail on it"
            )
        elif self.reply > MAX_SCALED:
            text += f"; the waits are not scaled beyond {MAX_SCALED:g} s"
        text += f"; a new connection is answered {self.setup * 1000:.0f} ms after its connect, beyond that"
        if self.greeting:
            text += (
                "; it answers nothing on a connection before that connection's CMD_CONNECT_TO_PLTF (erratum "
                "E-BEH-006, an alternative reading; zoo behaviour matrix row 9): every connection of the run sends "
                "CMD_CONNECT_TO_PLTF first"
            )
        if self.pipeline:
            text += f"; requests are sent one at a time ({self.pipeline})"
        else:
            text += "; it answers pipelined requests in order, and the run pipelines (erratum E-WIRE-008)"
        return text


def measure(target: Target, samples: int = 3, patience: float | None = None) -> Pace:
    """The target's pace (module rules); where nothing is answered within ``PATIENCE`` but a connection that greets
    with CMD_CONNECT_TO_PLTF is answered, the run greets on every connection (``Config.greeting``, E-BEH-006)."""
    patience = PATIENCE if patience is None else patience
    p = _measure(target, samples, patience)
    if p.reply is None and not target.config.greeting and _greets(target):
        target.config.greeting = True
        p = dataclasses.replace(_measure(target, samples, patience), greeting=True)
    return p


def _greets(target: Target) -> bool:
    """Whether a new connection answers CMD_GET_STATUS only after its CMD_CONNECT_TO_PLTF: of GET_STATUS,
    CONNECT_TO_PLTF, GET_STATUS in one write exactly one is answered (erratum E-BEH-006, zoo matrix row 9)."""
    cfg = target.config
    s = Session(cfg.host, target.port_of("A"), label="A", log=WireLog(max_entries=50), timeout=cfg.reply_timeout)
    answered = 0
    try:
        s.connect(timeout=min(cfg.reply_timeout, 5.0))
        s.send_many([build("request", n) for n in GREETING_PROBE], "GET_STATUS + CONNECT_TO_PLTF + GET_STATUS")
        for _ in range(2):
            s.read_reply("CMD_GET_STATUS")
            answered += 1
    except (TargetFailure, Unreachable):
        pass
    finally:
        s.close()
    return answered == 1


def _measure(target: Target, samples: int, patience: float) -> Pace:
    cfg = target.config
    deadline = time.monotonic() + cfg.connect_window
    while True:
        times: list[float] = []
        first, pipeline = 0.0, "not measured"
        s = Session(cfg.host, target.port_of("A"), label="A", log=WireLog(max_entries=50), timeout=patience)
        try:
            connected = time.monotonic()
            greet(s.connect(timeout=min(cfg.reply_timeout, 5.0)), cfg)
            for i in range(samples):
                t0 = time.monotonic()
                s.request(build("request", "CMD_GET_STATUS"), timeout=patience if i == 0 else max(3 * times[0], 1.0))
                times.append(time.monotonic() - t0)
                if i == 0:
                    first = time.monotonic() - connected
                if times[0] > MAX_SCALED:
                    break  # too slow to scale to: one sample says enough
            pipeline = _pipelined(s, max(3 * times[0], 1.0)) if times[0] <= MAX_SCALED else "a slow target"
        except (ConnectionClosed, Unreachable) as exc:  # turned away: the port is not free yet (one client per port)
            refused = "refused" in str(exc).lower()  # nothing listens: no use waiting
            if not times and not refused and time.monotonic() < deadline:
                time.sleep(0.05)
                continue
            if not times:
                return Pace(None, str(exc))
            pipeline = f"not measured: {exc}"
        except TargetFailure as exc:
            if not times:
                return Pace(None, str(exc))
            pipeline = f"not measured: {exc}"
        finally:
            s.close()
        reply = statistics.median(times)
        again = _answered_after_connect(target, min(patience, max(3 * first, 1.0))) if reply <= MAX_SCALED else None
        setup = max(first, again or 0.0) - reply
        return Pace(reply, pipeline=pipeline, setup=max(0.0, setup))


def _answered_after_connect(target: Target, timeout: float) -> float | None:
    """Wall s from the connect of a new connection to port A to the reply to its first CMD_GET_STATUS (a port
    that turns the newcomer away while it notices our last close is tried again); None when none came."""
    cfg = target.config
    deadline = time.monotonic() + cfg.connect_window
    while time.monotonic() < deadline:
        s = Session(cfg.host, target.port_of("A"), label="A", log=WireLog(max_entries=50), timeout=timeout)
        try:
            t0 = time.monotonic()
            greet(s.connect(timeout=min(cfg.reply_timeout, 5.0)), cfg)
            s.request(build("request", "CMD_GET_STATUS"))
            return time.monotonic() - t0
        except (ConnectionClosed, Unreachable):
            time.sleep(0.05)
        except TargetFailure:
            return None
        finally:
            s.close()
    return None


PIPELINE_PROBE = ("CMD_GET_STATUS", "CMD_GET_POSITION", "CMD_GET_POSITION")
GREETING_PROBE = ("CMD_GET_STATUS", "CMD_CONNECT_TO_PLTF", "CMD_GET_STATUS")


def _pipelined(s: Session, timeout: float) -> str:
    """'' when the requests of PIPELINE_PROBE, sent in one write, are answered in that order; else what happened."""
    try:
        s.exchange([build("request", name) for name in PIPELINE_PROBE], timeout=timeout)
    except TargetFailure as exc:
        return f"three requests in one write: {exc}"
    return ""


def apply(pace: Pace, config: Config) -> None:
    """Scale the run's waits to the measured reply time (see the module rules)."""
    config.reply_time = pace.reply
    config.pipeline = pace.reply is not None and not pace.pipeline
    if pace.reply is not None and pace.reply <= MAX_SCALED:
        config.setup_time = min(pace.setup, MAX_SCALED)
        config.min_wall = max(config.min_wall, WAIT_SCALE * pace.reply)
        config.probe_timeout = max(config.probe_timeout, SCALE * (pace.reply + config.setup_time))


def link(config: Config) -> str:
    """The link as measured at the start (``measure``), in wall and in simulated time: the reason an INCONCLUSIVE
    of a timed case names when the link may have kept the case from judging the target (issue 32: "where the link
    cannot keep a timed behaviour (the velocity watchdog) at the declared time scale, the case is INCONCLUSIVE with
    that reason")."""
    if config.reply_time is None:
        return f"the link's reply time was not measured (time scale {config.time_scale:g})"
    reply, setup, scale = config.reply_time, config.setup_time, config.time_scale
    return (
        f"the link answers in {reply * 1000:.0f} ms and a new connection {setup * 1000:.0f} ms after that, "
        f"measured at the start: {reply * scale:.2f} and {setup * scale:.2f} simulated s at time scale {scale:g}"
    )


def run_budget(config: Config) -> float:
    """The default budget of a smoke or standard run: 280 s (a run ends within 5 minutes), or twice what the
    standard tier needs against a healthy target at the declared time scale when that is more (about 40 s of
    requests and 300 simulated s of motion and waiting: 680 s at time scale 1)."""
    return max(280.0, 2 * (40.0 + 300.0 / config.time_scale))


def case_budget(config: Config) -> float:
    return config.case_budget if config.case_budget is not None else CASE_WALL + CASE_SIM / config.time_scale


@dataclass
class Watch:
    """Counts silent cases and decides whether the next case runs (see the module rules)."""

    silent_run: int = 0
    pace: str = ""  # what the early measurement found, when it explains the silence
    stuck_since: str = ""  # the first case of the silent run that tripped the watch ("" while not tripped)
    why: str = ""
    last_check: float = field(default=float("-inf"))
    _first: str = ""

    @property
    def tripped(self) -> bool:
        return bool(self.stuck_since)

    def record(self, case_id: str, silent: bool, why: str) -> None:
        if not silent:
            self.silent_run, self.stuck_since = 0, ""
            return
        self.silent_run += 1
        if self.silent_run == 1:
            self.why, self._first = why, case_id
        if self.silent_run >= STUCK_AFTER and not self.tripped:
            self.last_check = float("-inf")  # check at once
            self.stuck_since = self._first

    def blocks(self, target: Target) -> str:
        """'' when the next case may run; else why it is not run."""
        if not self.tripped:
            return ""
        now = time.monotonic()
        if now - self.last_check >= RECHECK:
            self.last_check = now
            problem = health(target)
            if not problem:
                self.silent_run, self.stuck_since = 0, ""
                return ""
            self.why = problem
        return (
            f"not run: the target stopped answering at {self.stuck_since} and still does not "
            f"({self.why}){'; ' + self.pace if self.pace else ''}"
        )


def health(target: Target) -> str:
    """'' when port A takes a new client and answers CMD_GET_STATUS within the reply timeout; else the problem."""
    cfg = target.config
    target.close()  # one client per port: our own sessions would keep the port busy
    try:
        target.connect(
            "A",
            WireLog(max_entries=50),
            NullObserver(),
            window=min(cfg.connect_window, 2.0),
            probe_timeout=cfg.reply_timeout,
        ).close()
    except Unreachable as exc:
        return str(exc)
    return ""
