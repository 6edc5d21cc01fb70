"""The behaviours the guide allows (the zoo's behaviour matrix, zoo/README.md; errata E-BEH-*) are judged as such:
NON-STRICT or a run note naming the erratum or the matrix row, never FAIL, never ERROR (issue 32)."""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from collections.abc import Callable

import pytest

from pltf.conformance_tests import pace
from pltf.conformance_tests import target as target_side
from pltf.conformance_tests.catalogue import Case, Level, Tier, Verdict, load_all, select
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.runner import Runner, RunResult
from pltf.conformance_tests.target import Config
from pltf.harness import launch
from pltf.zoo.members import MEMBERS
from tests.conformance_tests.fakes import TinyTarget

SCALE = 10.0
FEW = ("6.2/framing/header-and-length", "6.1/ports/reconnect", "6.3/CMD_SET_MODE/in-running")


def _run(member: str, upstream: str, cases: list[str] | None = None, scale: float = SCALE, **kw: object) -> RunResult:
    with launch.zoo(member, upstream=upstream, time_scale=scale) as target:
        host = MEMBERS[member].host
        config = Config(host, target.ports[0], target.ports[1], time_scale=scale, simulator=True, **kw)  # type: ignore[arg-type]
        chosen = (
            [load_all()[c] for c in cases] if cases is not None else select(load_all().values(), tier=Tier.STANDARD)
        )
        return Runner(config, chosen).run()


def _bad(run: RunResult) -> list[str]:
    return [
        f"{r.case.id}: {r.verdict} {r.message.splitlines()[0] if r.message else ''}"
        for r in run.results
        if r.verdict in (Verdict.FAIL, Verdict.ERROR)
    ]


def test_a_target_that_answers_nothing_before_connect_is_greeted_on_every_connection(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Row 9 (E-BEH-006): the run notices at its start, says so, and greets on every connection it opens - a
    reconnections included; before, every case failed on a reply timeout and the rest were not run."""
    monkeypatch.setattr(pace, "PATIENCE", 1.5)  # the first GET_STATUS's patience: the run's 15 s, shortened here
    run = _run("silent-until-connect", "emulator", list(FEW), reply_timeout=1.5)
    assert not _bad(run), _bad(run)
    assert [r.verdict for r in run.results] == [Verdict.PASS] * len(FEW), [(r.case.id, r.message) for r in run.results]
    assert any("E-BEH-006" in n and "matrix row 9" in n for n in run.notes), run.notes


BEHAVIOURS = sorted(m for m, member in MEMBERS.items() if member.conforming and m not in ("absurd-values",))


@pytest.mark.slow
@pytest.mark.parametrize("member", BEHAVIOURS)
def test_the_standard_tier_through_each_conforming_behaviour_has_no_fail_and_no_error(member: str) -> None:
    """What must hold for every row: the standard tier ends with no FAIL and no ERROR the behaviour causes (the
    velocity cases of a loaded machine may end INCONCLUSIVE: re-run, never FAIL); the original profile where the
    member's reading needs it."""
    run = _run(member, "reference", profile=MEMBERS[member].profile)
    assert not _bad(run), _bad(run)


# back in the default tier: the two clean-clone make test runs of 2026-11-28 that saw the relay not serving again
# within the probe's 5 s met the member's own fault (a restart left the dropped clients' pumps in its selector and
# it accepted and closed newcomers after its first restart: tests/zoo/test_relay), not the suite's
def test_a_case_during_which_the_target_restarts_is_run_again() -> None:
    """Row 10 (E-BEH-007) through the zoo member: the restart drops the connection (or leaves it unanswered) and the
    port refuses while the target starts again; the suite waits it out, counts the restart and runs the case again
    (before: FAIL 'the target closed the connection'). About 6 s: a restart 2 s after the start, 2 s down."""
    attempts: list[str] = []

    def until_restart(ctx: CaseContext) -> None:
        attempts.append(ctx.case.id)
        deadline = time.monotonic() + 20.0  # the member restarts every 2 s (its start-up and a loaded machine: more)
        while len(attempts) == 1 and time.monotonic() < deadline:
            ctx.status()
            time.sleep(0.05)
        ctx.status()

    case = Case("6.1/t/restart", until_restart, "a test case", Level.MUST, Tier.SMOKE, "state")
    with launch.zoo("restarts", upstream="emulator", time_scale=SCALE, extra=["--restart-every", "2"]) as target:
        config = Config("127.0.0.1", target.ports[0], target.ports[1], time_scale=SCALE, simulator=True)
        run = Runner(config, [case]).run()
    result = run.results[0]
    assert result.verdict is Verdict.PASS and result.message.startswith("passed on attempt"), result.message
    assert "the target restarted during this case" in result.attempts[0].message
    assert "E-BEH-007" in result.attempts[0].message and "matrix row 10" in result.attempts[0].message
    assert any("E-BEH-007" in n and "during 6.1/t/restart" in n for n in run.notes), run.notes


def test_a_fin_that_ends_the_session_is_named_as_the_reading_it_is() -> None:
    """Row 1 (E-BEH-001): the MAY case that half-closes after a request is N/A and says which reading the target
    follows and what was seen, never FAIL."""
    run = _run("fin-ends-session", "emulator", ["6.2/framing/half-close-complete"])
    result = run.results[0]
    assert result.verdict is Verdict.NA, result.message
    assert result.message.startswith("the target ends the session at our FIN (erratum E-BEH-001"), result.message
    assert "matrix row 1" in result.message and "sent CMD_GET_STATUS, the target closed" in result.message


@pytest.mark.slow
def test_the_standard_tier_through_a_100_ms_accept_loop_passes_at_time_scale_1() -> None:
    """Row 5 at a real platform's pace (time scale 10: the parametrized test above); about 5 minutes."""
    run = _run("slow-accept", "reference", scale=1.0)
    assert run.exit_code == 0, _bad(run) + [f"{r.case.id}: {r.message}" for r in run.results if r.blocking]


class LateClose(TinyTarget):
    """TinyTarget that closes on malformed input only ``delay`` s later (a relay on a loaded machine)."""

    def __init__(self, delay: float) -> None:
        super().__init__()
        self.delay = delay

    def _serve(self, conn: socket.socket) -> None:
        super()._serve(conn)
        time.sleep(self.delay)


def test_a_close_on_malformed_input_that_comes_after_the_wait_is_still_the_close() -> None:
    """Through slow-accept at load 21 two framing cases were NON-STRICT 'the connection stayed open but the target
    stopped answering': the close came after the 0.25 s wait, while the suite asked for the status."""
    with LateClose(0.6) as tiny:
        config = Config("127.0.0.1", tiny.ports[0], tiny.ports[1], time_scale=10.0, reply_timeout=2.0)
        run = Runner(config, [load_all()["6.2/framing/trailing-bytes"]]).run()
    assert run.results[0].verdict is Verdict.PASS, run.results[0].message


class Restarting(TinyTarget):
    """TinyTarget that restarts on ``restart(down)``: every connection dropped, the ports refused for ``down`` s
    (0: listening again at once), the state lost (Not connected) - zoo matrix row 10 in-process, timed by the test.
    ``close_on`` names a command at which it closes the connection without a reply and without a restart (a fault
    the suite must still FAIL)."""

    def __init__(self, close_on: str = "") -> None:
        super().__init__()
        self.close_on = close_on
        self.conns: set[socket.socket] = set()
        self.timers: list[threading.Timer] = []  # a restart's pending listen-again, cancelled at exit

    def _run(self, conn: socket.socket, index: int) -> None:
        self.conns.add(conn)
        try:
            super()._run(conn, index)
        finally:
            self.conns.discard(conn)

    def handle(self, t: object) -> object:
        if getattr(t, "NAME", "") == self.close_on:
            raise ConnectionAbortedError("closed at " + self.close_on)  # _run closes the connection
        return super().handle(t)

    def restart(self, down: float) -> None:
        for ls in self._listeners:
            with contextlib.suppress(OSError):
                ls.shutdown(socket.SHUT_RDWR)  # wakes the accept loop: the port stops listening at once
            ls.close()
        for conn in list(self.conns):
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)
        with self.lock:
            self.state, self.mode = St.NOT_CONNECTED, 0
        if down:
            self.timers.append(timer := threading.Timer(down, self._listen_again))
            timer.start()
        else:
            self._listen_again()

    def __exit__(self, *exc: object) -> None:
        """Listening sockets a restart's timer would open after the test are never opened (a clean clone's make
        test: two of them, left to the collector, failed a later test under filterwarnings=error)."""
        for timer in self.timers:
            timer.cancel()
            if timer is not threading.current_thread():
                timer.join()
        super().__exit__(*exc)

    def _listen_again(self) -> None:
        if self._stop.is_set():
            return
        self._listeners = []
        for port in self.ports:
            ls = socket.socket()
            ls.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            ls.bind(("127.0.0.1", port))
            ls.listen(8)
            self._listeners.append(ls)
        for i, ls in enumerate(self._listeners):
            threading.Thread(target=self._accept, args=(ls, i), daemon=True).start()


def _tiny_run(target: Restarting, func: Callable[[CaseContext], None], level: Level = Level.MUST) -> RunResult:
    case = Case("6.1/t/restart", func, "a test case", level, Tier.SMOKE, "state")
    config = Config(
        "127.0.0.1",
        target.ports[0],
        target.ports[1],
        time_scale=10.0,
        reply_timeout=1.0,
        connect_window=1.0,
        min_wall=0.05,
    )
    return Runner(config, [case]).run()


def _cut(target: Restarting, down: float, times: int = 1) -> tuple[Callable[[CaseContext], None], list[int]]:
    """A case that needs Ready and reads the status; the target restarts in its first ``times`` attempts."""
    attempts: list[int] = []

    def case(ctx: CaseContext) -> None:
        ctx.ready()
        attempts.append(1)
        if len(attempts) <= times:
            target.restart(down)
        s = ctx.status()
        assert s.op == target_side.OperationState.ST_OP_READY, s.describe()

    return case, attempts


@pytest.mark.parametrize("down", [0.6, 0.0], ids=["refused-for-a-while", "back-at-once"])
def test_a_case_a_restart_cut_is_run_again_from_scratch_and_passes(down: float) -> None:
    """Row 10 (E-BEH-007) in-process: the connection dropped, the port refused for a while (or listening again at
    once: then the lost initialisation tells the restart), the state lost. The cut attempt is INCONCLUSIVE naming
    the restart, the re-run brings the fresh target to Ready itself and passes; the notes name the case."""
    with Restarting() as target:
        func, attempts = _cut(target, down)
        run = _tiny_run(target, func)
    result = run.results[0]
    assert (result.verdict, result.message, len(attempts)) == (Verdict.PASS, "passed on attempt 2", 2), result.message
    first = result.attempts[0].message
    assert first.startswith("the target restarted during this case") and "matrix row 10" in first, first
    seen = "refused connections for" if down else "lost our connection and the platform its initialisation"
    assert seen in first, first
    assert any("during 6.1/t/restart" in n and "E-BEH-007" in n for n in run.notes), run.notes
    assert run.notes[-1].startswith("the target restarted 1 time(s) during the run"), run.notes[-1]
    assert run.exit_code == 0


def test_a_case_a_restart_cuts_every_time_stays_inconclusive_never_fail() -> None:
    with Restarting() as target:
        func, attempts = _cut(target, 0.3, times=99)
        run = _tiny_run(target, func)
    result = run.results[0]
    assert result.verdict is Verdict.INCONCLUSIVE and len(attempts) == 3, (result.verdict, result.message)
    assert result.message.startswith("the target restarted during this case"), result.message


@pytest.mark.parametrize("how", ["closes", "closes-after-shutdown"])
def test_a_closed_connection_that_is_no_restart_still_fails(how: str) -> None:
    """The restart check must not excuse a real fault: a target that closes the connection at CMD_GET_POSITION (its
    state kept), or one that closes it after the case's CMD_SHUTDOWN_PLTF (the initialisation lost by the case's
    own command, not by a restart), FAILs."""

    def case(ctx: CaseContext) -> None:
        ctx.ready()
        if how == "closes-after-shutdown":
            ctx.send("CMD_SHUTDOWN_PLTF")
        ctx.position()

    with Restarting(close_on="CMD_GET_POSITION") as target:
        run = _tiny_run(target, case)
    result = run.results[0]
    assert result.verdict is Verdict.FAIL, (result.verdict, result.message)
    assert "closed the connection" in result.message and "restarted" not in result.message, result.message
    assert not any("E-BEH-007" in n for n in run.notes), run.notes


def test_a_port_that_does_not_come_back_is_named_with_how_long_it_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(target_side, "RESTART_WINDOW", 1.5)
    with Restarting() as target:
        func, _ = _cut(target, 60.0)
        run = _tiny_run(target, func)
    message = run.results[0].message
    assert run.results[0].verdict in (Verdict.FAIL, Verdict.INCONCLUSIVE), message
    assert "refused connections for 1." in message and "after it had served this run" in message, message
