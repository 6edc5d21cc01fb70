"""The velocity cases through a link that serves a new connection late (issue 32, zoo behaviour matrix row 5: the
accept loop of a GUI application runs every 100 ms, a simulated second at time scale 10, past the 0.5 s velocity
watchdog): they feed the watchdog from the one connection they hold and judge the target, not the link - and a
target that does not move, moves at the wrong speed or keeps moving still FAILs behind that link.

The judgement's rule is tested on its own too (``poses.Held``): a late resend of the suite excuses a dip below
the commanded velocity, never a target that does not move or never reaches it."""

from __future__ import annotations

import re
import time
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from pltf.conformance_tests import pace, poses
from pltf.conformance_tests.catalogue import Case, Level, Tier, Verdict, load_all
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.mutants.catalogue import DropRequest, RewriteRequest, WireMutant
from pltf.conformance_tests.mutants.proxy import Conn, FrameProxy
from pltf.conformance_tests.outcome import Fail, Inconclusive
from pltf.conformance_tests.poses import Pose
from pltf.conformance_tests.runner import Runner, RunResult
from pltf.conformance_tests.target import Config, Target
from pltf.harness import launch
from pltf.spec.codec import build, decode_frame, encode, frame
from tests.conformance_tests.relays import Relay

SCALE = 10.0
ACCEPT_EVERY = 0.1  # s: the timer-driven accept of zoo member slow-accept
VELOCITY = ("4.3/MODE_MOTION_VEL/move-vel-wheel", "4.3/MODE_MOTION_VEL/move-vel", "4.3/MODE_MOTION_VEL/watchdog")


# ---- the judgement, on samples made up here


def _ctx(reply: float = 0.04, setup: float = 0.1) -> CaseContext:
    cfg = Config("127.0.0.1", 1, 2, time_scale=SCALE, reply_time=reply, setup_time=setup)
    case = Case("4.3/t/held", lambda ctx: None, "a test case", Level.MUST, Tier.SMOKE, "motion")
    return CaseContext(Target(cfg), case)


def _line(vs: list[float]) -> list[Pose]:
    """Poses 0.1 simulated s apart along x at the velocities ``vs`` (mm/s)."""
    x, out = 0.0, []
    for v in vs:
        x += v * 0.1
        out.append(Pose(x, 0.0, 0.0, v))
    return out


def test_a_late_resend_turns_a_dip_below_the_commanded_velocity_into_an_inconclusive_naming_the_link() -> None:
    ctx = _ctx()
    held = poses._held(
        ctx, "CMD_MOVE_VEL", _line([200.0] * 6 + [0.0] * 6), None, worst_gap=0.6, spread=(0.1, 0.2), limit=0.5
    )
    assert held.void and not held.stale
    with pytest.raises(Inconclusive) as exc:
        held.fail("velocity 0 mm/s", dipped=held.dipped(0.0, 200, "v"))
    text = str(exc.value)
    assert text.startswith("velocity 0 mm/s; but the suite resent CMD_MOVE_VEL 0.60 simulated s apart"), text
    assert "answers in 40 ms and a new connection 100 ms after that" in text and "time scale 10" in text, text


@pytest.mark.parametrize(
    ("what", "vs", "value"),
    [
        ("never moved", [0.0] * 12, 0.0),
        ("never reached the velocity", [100.0] * 12, 100.0),
        ("too fast", [300.0] * 12, 300.0),
    ],
)
def test_a_late_resend_excuses_no_target_that_never_moves_or_never_reaches_the_velocity(
    what: str, vs: list[float], value: float
) -> None:
    held = poses._held(_ctx(), "CMD_MOVE_VEL", _line(vs), None, worst_gap=0.6, spread=(0.1, 0.2), limit=0.5)
    with pytest.raises(Fail) as exc:
        held.fail(f"{what}: velocity {value:.0f} mm/s", dipped=held.dipped(value, 200, "v"))
    assert not isinstance(exc.value, Inconclusive)


def test_a_target_that_answered_in_bursts_of_one_stale_pose_is_inconclusive_only_if_it_moved() -> None:
    stale = [Pose(0.0, 0.0, 0.0, 200.0)] * 8 + [Pose(150.0, 0.0, 0.0, 0.0)] * 4
    held = poses._held(_ctx(), "CMD_MOVE_VEL", stale, None, worst_gap=0.1, spread=(0.1, 0.2), limit=0.5)
    assert held.stale and "12 poses read, only 2 distinct" in held.void and "time scale 10" in held.void
    standing = poses._held(
        _ctx(), "CMD_MOVE_VEL", [Pose(0.0, 0.0, 0.0)] * 12, None, worst_gap=0.6, spread=(0.1, 0.2), limit=0.5
    )
    assert standing.void == ""


def test_a_target_that_stood_still_answering_nothing_for_the_whole_hold_is_not_judged_one_that_answers_is() -> None:
    standing = [Pose(0.0, 0.0, 0.0)] * 12
    stalled = poses._held(_ctx(), "CMD_MOVE_VEL", standing, None, 0.1, spread=(0.3, 2.0), limit=0.5, held_for=1.5)
    assert stalled.stale and "answered a pose 2.00 simulated s after it was asked, 1.60 s more than" in stalled.void
    prompt = poses._held(_ctx(), "CMD_MOVE_VEL", standing, None, 0.1, spread=(0.3, 0.6), limit=0.5, held_for=1.5)
    assert prompt.void == ""


def test_the_link_as_measured_is_described_in_wall_and_simulated_time() -> None:
    cfg = Config("h", 1, time_scale=SCALE, reply_time=0.036, setup_time=0.118)
    assert pace.link(cfg) == (
        "the link answers in 36 ms and a new connection 118 ms after that, measured at the start: 0.36 and 1.18 "
        "simulated s at time scale 10"
    )


# ---- through a 100 ms accept loop in front of the reference server (or a mutant of it)


class HalfWheels(RewriteRequest):
    """The platform drives its wheels at half the commanded velocity."""

    def __init__(self) -> None:
        super().__init__("CMD_MOVE_VEL_WHEEL", _half)


def _half(data: bytes) -> bytes:
    t = decode_frame(frame(data), "request")
    half = build("request", t.NAME, vel_right=t.vel_right // 2, vel_left=t.vel_left // 2)  # type: ignore[attr-defined]
    return encode(half)[8:]


@contextmanager
def _slow_accept(patch: str | None = None, wire: WireMutant | None = None) -> Iterator[list[int]]:
    with (
        launch.reference(time_scale=SCALE, mutant=patch) as server,
        FrameProxy("127.0.0.1", server.ports, wire) as proxy,
        Relay(proxy.ports, accept_every=ACCEPT_EVERY) as relay,
    ):
        yield relay.ports


def _run(ports: list[int], cases: tuple[str, ...]) -> RunResult:
    config = Config("127.0.0.1", ports[0], ports[1], time_scale=SCALE, simulator=True)
    return Runner(config, [load_all()[c] for c in cases]).run()


def test_the_velocity_cases_through_a_100_ms_accept_loop_judge_the_target_not_the_link() -> None:
    """Before the cases held their connection: FAIL "CMD_MOVE_VEL(300 mm/s): velocity 0 mm/s" (issue 32). On a
    loaded machine a case may still be INCONCLUSIVE, but then it names the link as measured and the time scale, or
    it passed on one attempt of its re-runs (flaky: a machine at load 10 stalls the target past its watchdog, which
    no pose read from the client can always tell from a link's delay)."""
    with _slow_accept() as ports:
        run = _run(ports, VELOCITY)
    assert "a new connection is answered" in run.notes[0], run.notes
    for r in run.results:
        assert r.verdict in (Verdict.PASS, Verdict.INCONCLUSIVE), (r.case.id, r.verdict, r.message)
        if r.verdict is Verdict.INCONCLUSIVE:
            named = "time scale 10" in r.message and "the link answers in" in r.message
            assert named or _passed_once(r.message), (r.case.id, r.message)


def _passed_once(message: str) -> bool:
    """The runner's word for a case whose re-runs disagree, at least one of them a PASS (runner._resolve)."""
    m = re.match(r"flaky: (\d+) of \d+ attempts passed", message)
    return m is not None and int(m.group(1)) >= 1


WHEELS, VEL, WATCHDOG = VELOCITY
MOVE_VEL_WHEEL = "CMD_MOVE_VEL_WHEEL"


class StallOnce(WireMutant):
    """The link stalls once: the first reply after the first CMD_MOVE_VEL_WHEEL comes ``stall`` wall s late (a
    loaded machine descheduling the target or a relay), everything after it on time."""

    wants_client_frames = True

    def __init__(self, stall: float) -> None:
        self.stall, self.armed, self.spent = stall, False, False

    def client_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        self.armed = self.armed or (not self.spent and decode_frame(data, "request").NAME == MOVE_VEL_WHEEL)
        conn.to_server(data)

    def server_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        if self.armed and decode_frame(data, "reply").NAME == "CMD_GET_POSITION":
            self.armed, self.spent = False, True
            time.sleep(self.stall)
        conn.to_client(data)


def test_one_reply_later_than_the_window_does_not_make_the_watchdog_case_call_a_moving_target_unmoved() -> None:
    """Hog run 12: NON-STRICT "precondition: one CMD_MOVE_VEL_WHEEL did not set the platform moving ((2100, 10001,
    0.2 deg, v 0, w 0.000))": the one pose read in the 2 simulated s after the command (0.2 wall s at time scale
    10) was the one asked right after it. Here the link holds that reply 0.4 wall s."""
    with _slow_accept(wire=StallOnce(0.4)) as ports:
        run = _run(ports, (WATCHDOG,))
    r = run.results[0]
    assert r.verdict in (Verdict.PASS, Verdict.INCONCLUSIVE), (r.verdict, r.message)
    if r.verdict is Verdict.INCONCLUSIVE:
        assert "time scale 10" in r.message, r.message


@pytest.mark.parametrize(
    ("mutant", "case_id", "verdict", "seen"),
    [
        ({"wire": DropRequest(MOVE_VEL_WHEEL)}, WHEELS, Verdict.FAIL, "wheels at 200 mm/s: translational velocity"),
        ({"wire": HalfWheels()}, WHEELS, Verdict.FAIL, "wheels at 200 mm/s: translational velocity"),
        ({"wire": DropRequest("CMD_MOVE_VEL")}, VEL, Verdict.FAIL, "CMD_MOVE_VEL(300 mm/s): velocity"),
        # a SHOULD requirement (erratum E-PAR-018): NON-STRICT is its failing verdict
        ({"patch": "no_watchdog"}, WATCHDOG, Verdict.NON_STRICT, "one CMD_MOVE_VEL_WHEEL and no more: still moving"),
    ],
    ids=["does-not-move", "half-speed", "move-vel-ignored", "no-watchdog"],
)
def test_a_target_that_does_not_move_moves_at_half_speed_or_keeps_moving_fails_behind_the_same_link(
    mutant: dict[str, object], case_id: str, verdict: Verdict, seen: str
) -> None:
    with _slow_accept(**mutant) as ports:  # type: ignore[arg-type]
        run = _run(ports, (case_id,))
    r = run.results[0]
    if r.verdict is Verdict.INCONCLUSIVE and mutant.get("wire").__class__ is HalfWheels:
        # a simulator starved by a loaded machine answers a few stale poses: too few to tell half speed from a
        # stop of its watchdog - never a PASS, and the reason named (on a quiet machine: FAIL)
        assert "poses read, only" in r.message and "time scale 10" in r.message, r.message
        return
    assert r.verdict is verdict and r.message.startswith(seen), (r.verdict, r.message)
