"""Poses and the motion helpers of the motion cases (cases/motion.py, cases/motion_ignored.py): reading the pose,
driving back to the start, waiting for rest, holding a velocity against the watchdog and judging what was seen.

Rules of this module:
- Every motion case drives back to its start pose (MOVE_ABS in mode Automatic) in a finalizer (``begin``
  registers ``go_back``); the estimated pose is never reset after a real motion.
- Tolerances are generous (errata E-PAR-021: the suite's bounds, not the platform's): position 100 mm, angle
  5 degrees, velocity 15 % + 30 mm/s; time limits allow for a slow platform (100 mm/s) plus 10 s.
- "No motion" means less than 20 mm and 1 degree in 1 simulated second (localization noise, E-MOT-004), with
  velocities under 5 mm/s and 0.02 rad/s; a move that was executed goes 300 mm or more.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NoReturn

from pltf.conformance_tests import pace, reported
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Fail, Inconclusive
from pltf.conformance_tests.target import MotionMode
from pltf.conformance_tests.wire import Session
from pltf.spec.codec import build
from pltf.spec.telegram import Telegram

NO, VEL, JOYSOFT = MotionMode.MODE_MOTION_NO, MotionMode.MODE_MOTION_VEL, MotionMode.MODE_MOTION_JOYSOFT
AUTO, JOYHARD = MotionMode.MODE_MOTION_AUTOMATIC, MotionMode.MODE_MOTION_JOYHARD
POS_TOL, ANG_TOL = 100.0, math.radians(5.0)
# "still": what a standing platform's estimate may do under localization noise (E-MOT-004), far below any move
STILL_POS, STILL_ANG, STILL_V, STILL_W = 20.0, math.radians(1.0), 5.0, 0.02
MOVED = 50.0  # mm from where it stood: the platform moved (beyond localization noise, STILL_POS)
STOP_WITHIN = 3.0  # simulated s a halted platform may take to come to rest


def angle_diff(a: float, b: float) -> float:
    """a - b in (-pi, pi] (radians)."""
    d = math.fmod(a - b, 2 * math.pi)
    if d <= -math.pi:
        d += 2 * math.pi
    elif d > math.pi:
        d -= 2 * math.pi
    return d


@dataclass(frozen=True)
class Pose:
    x: float
    y: float
    th: float  # rad
    v: float = 0.0  # mm/s
    w: float = 0.0  # rad/s

    def ahead(self, forward: float, left: float = 0.0, turn_deg: float = 0.0) -> Pose:
        c, s = math.cos(self.th), math.sin(self.th)
        return Pose(self.x + c * forward - s * left, self.y + s * forward + c * left, self.th + math.radians(turn_deg))

    def dist(self, other: Pose) -> float:
        return math.hypot(self.x - other.x, self.y - other.y)

    def describe(self) -> str:
        return f"({self.x:.0f}, {self.y:.0f}, {math.degrees(self.th):.1f} deg, v {self.v:.0f}, w {self.w:.3f})"


def pose(ctx: CaseContext) -> Pose:
    return _pose_of(ctx.position())


def _pose_of(p: Any) -> Pose:
    """A CMD_GET_POSITION reply as a Pose (its values plausible: reported.py, else the case FAILs naming them)."""
    reported.position(p)
    return Pose(p.x, p.y, p.angle, p.vel_trans, p.vel_rot)


def _milli(th: float) -> int:
    return round(math.degrees(th) * 1000)


def go_back(ctx: CaseContext, start: Pose) -> None:
    """Drive back to ``start`` in mode Automatic, then stop (a finalizer of every motion case)."""
    ctx.ensure(St.RUNNING, AUTO)
    ctx.send("CMD_MOVE_ABS", x=round(start.x), y=round(start.y), angle=_milli(start.th))
    at_pose(ctx, start, "driving back to the start pose")
    ctx.ready()


def begin(ctx: CaseContext, mode: int) -> Pose:
    ctx.ensure(St.RUNNING, mode)
    start = rest(ctx)
    ctx.on_exit("drive back to the start pose", lambda: go_back(ctx, start))
    return start


def rest(ctx: CaseContext, within: float = 10.0) -> Pose:
    p = ctx.poll(lambda: pose(ctx), lambda q: abs(q.v) < STILL_V and abs(q.w) < STILL_W, within=within)
    if abs(p.v) >= STILL_V or abs(p.w) >= STILL_W:
        raise Fail(f"the platform did not come to rest within {within:g} s: {p.describe()}")
    return p


def at_pose(ctx: CaseContext, target: Pose, how: str, *, check_angle: bool = True) -> Pose:
    limit = target.dist(pose(ctx)) / 100.0 + 15.0

    def there(p: Pose) -> bool:
        return (
            p.dist(target) <= POS_TOL
            and (not check_angle or abs(angle_diff(p.th, target.th)) <= ANG_TOL)
            and abs(p.v) < 3.0
            and abs(p.w) < 0.02
        )

    p = ctx.poll(lambda: pose(ctx), there, within=limit)
    if not there(p):
        raise Fail(
            f"{how}: target {target.describe()} not reached within {limit:.0f} s - the platform is at "
            f"{p.describe()} ({p.dist(target):.0f} mm, "
            f"{math.degrees(angle_diff(p.th, target.th)):.1f} deg away)"
        )
    return p


def still(ctx: CaseContext, start: Pose, how: str, seconds: float = 1.0) -> None:
    ctx.sleep(seconds)
    judge_still(pose(ctx), start, how)


def judge_still(p: Pose, start: Pose, how: str) -> None:
    """``p``, read a while after ``how``, is where the platform stood (``start``), at rest."""
    if (
        p.dist(start) > STILL_POS
        or abs(angle_diff(p.th, start.th)) > STILL_ANG
        or abs(p.v) > STILL_V
        or abs(p.w) > STILL_W
    ):
        raise Fail(f"{how} must not move the platform: it went from {start.describe()} to {p.describe()}")


def watchdog(ctx: CaseContext, key: str = "VelWatchdogTime", default: float = 0.5) -> float:
    """The target's velocity watchdog in s, when it lists it (erratum E-PAR-018), else ``default``."""
    for p in ctx.get("CMD_GET_PLTF_PARAM_VEC").parameters:  # type: ignore[attr-defined]
        if p.key == key:
            return reported.number(p.value, f"the parameter {key} [ms]", lo=0.0, hi=3_600_000.0) / 1000.0
    return default


DISTINCT = 4  # distinct poses a hold needs to judge a platform that moved (``_held``)
IN_FLIGHT = 3  # CMD_GET_POSITIONs a hold keeps in flight at most on a fast link (more on a slow one: ``hold``)


@dataclass(frozen=True)
class Held:
    """What ``hold`` saw: the poses sampled, the CMD_GET_STATUS asked with the last send (when asked for), and why
    the samples may not show what the target does (``void``, '' when they do; ``stale`` when they may not show it
    at all, else only a stop the suite's own late resend could have let the watchdog make)."""

    samples: list[Pose]
    status: Telegram | None = None
    void: str = ""
    stale: bool = False

    def reached(self, want: float, axis: str) -> bool:
        """Some sample showed the commanded velocity ``want`` (``axis`` "v": mm/s, "w": rad/s)."""
        near = _NEAR[axis]
        return any(near(getattr(p, axis), want) for p in self.samples)

    def dipped(self, value: float, want: float, axis: str) -> bool:
        """``value`` fell short of ``want`` (between standing and it) though some sample reached ``want``: what a
        watchdog stop between two late resends makes of a target that keeps the velocity."""
        return -_STILL[axis] < value < want and self.reached(want, axis)

    def fail(self, message: str, *, dipped: bool, erratum: str | None = None) -> NoReturn:
        """Judge against the target: FAIL, or INCONCLUSIVE naming why the samples cannot tell (the link or the
        machine, not the target). Stale samples (a burst) excuse any verdict; a late resend excuses only what the
        watchdog can make of a target that keeps the velocity - a dip (``dipped``: short of the commanded value,
        though some sample reached it). A target that never moves, or never reaches the velocity, FAILs
        whatever the suite's pace."""
        if self.void and (self.stale or dipped):
            raise Inconclusive(f"{message}; but {self.void}")
        raise Fail(message, erratum=erratum)


def hold(
    ctx: CaseContext,
    name: str,
    fields: dict[str, Any],
    seconds: float,
    period: float = 0.1,
    limit: float | None = None,
    status: bool = False,
) -> Held:
    """Send ``name`` every ``period`` simulated seconds for ``seconds`` on the connection held; the poses sampled in
    between. ``status``: a CMD_GET_STATUS leaves with the last send (a status asked once the poses were read came a
    reply time after the last send: through a slow link past the watchdog, issue 17).

    The sends keep to their schedule whatever the replies do: the poses (a CMD_GET_POSITION after a send while
    fewer than ``IN_FLIGHT`` are unanswered - on a slow link as many as its measured reply time spans, so one still
    leaves every period) are read as they come, between two sends, never waited for (before, a fast target's
    reply was waited for after each send: on a loaded machine the gap between two sends grew past the watchdog
    and the case was INCONCLUSIVE). A target answers a connection's requests in order, so each pose is the one
    after its send; the few in flight keep a loaded simulator from falling behind a stream of requests.
    Every send goes on the one connection held (issue 32): a new one would be answered only after the link's
    set-up (a timer-driven accept: 100 ms, a simulated second at time scale 10, past the watchdog), so a lost
    connection ends the hold (the target closed it) instead of a silent reconnect.
    When the suite fell behind (the gap between two sends, in simulated time, reached 0.8 of ``limit``, the
    target's watchdog) or the target answered in bursts of one stale pose, ``Held.void`` says so, naming the
    link as measured and the time scale; the case judges as it would, and a verdict against the target that the
    void explains is INCONCLUSIVE (the runner re-runs), not FAIL.
    """
    session = ctx.session()
    scale = ctx.config.time_scale
    tick = period / scale  # wall s between two sends
    in_flight = max(IN_FLIGHT, math.ceil((ctx.config.reply_time or 0.0) / tick) + 1)
    command = build("request", name, **fields)
    ask = build("request", "CMD_GET_POSITION")
    samples: list[Pose] = []
    asked: deque[float] = deque()  # when each CMD_GET_POSITION still unanswered left
    waited: list[float] = []  # wall s each answered one took
    worst_gap, last = 0.0, None
    due = time.monotonic()
    for _ in range(max(1, round(seconds / period))):
        _read_until(session, due, asked, samples, waited)
        now = time.monotonic()
        session.send(command)  # on the connection held: a new one would starve the watchdog for its set-up
        worst_gap, last = max(worst_gap, (now - (last or now)) * scale), now
        if len(asked) < in_flight:
            session.send(ask)
            asked.append(time.monotonic())
        due = max(due + tick, now + tick / 2)  # fallen behind: on from now, no burst of sends to catch up
    if status:
        session.send(build("request", "CMD_GET_STATUS"))
    _read_until(session, due, asked, samples, waited)
    while asked:
        samples.append(_pose_of(session.read_reply("CMD_GET_POSITION")))
        waited.append(time.monotonic() - asked.popleft())
    st = session.read_reply("CMD_GET_STATUS") if status else None
    spread = (min(waited) * scale, max(waited) * scale)
    return _held(ctx, name, samples, st, worst_gap, spread, limit, held_for=seconds)


def _read_until(session: Session, until: float, asked: deque[float], samples: list[Pose], waited: list[float]) -> None:
    """Read the poses that come before wall time ``until`` (none waited for past it), and how long each took."""
    while True:
        now = time.monotonic()
        if asked and session.pending():
            samples.append(_pose_of(session.read_reply("CMD_GET_POSITION")))
            waited.append(time.monotonic() - asked.popleft())
        elif now >= until:
            return
        else:
            time.sleep(min(0.002, until - now))


def _distinct(samples: list[Pose]) -> list[Pose]:
    """``samples`` without a pose answered again (the same x, y and angle as the one before: read late)."""
    return [
        p
        for i, p in enumerate(samples)
        if i == 0 or (p.x, p.y, p.th) != (samples[i - 1].x, samples[i - 1].y, samples[i - 1].th)
    ]


def _held(
    ctx: CaseContext,
    name: str,
    samples: list[Pose],
    st: Telegram | None,
    worst_gap: float,
    spread: tuple[float, float],
    limit: float | None,
    held_for: float | None = None,
) -> Held:
    """``Held``, void when the samples may not show the target (``hold``): only where the platform moved at all -
    a target that does not move is judged on that, whatever the suite's pace. A pose answered again (the same
    x, y, angle as the one before) is the same observation, read late: a loaded simulator answers the requests
    between two of its ticks with one pose; only the first counts, and fewer than ``DISTINCT`` cannot tell. A
    platform that did not move is judged so unless the target answered nothing for longer than the hold beyond
    the link's reply time (``held_for``): a target that stood still for the whole hold (a loaded machine) cannot
    be told from one that does not move - a target that answers on time and does not move FAILs."""
    first = samples[0]
    moved = any(
        p.dist(first) > STILL_POS or abs(angle_diff(p.th, first.th)) > STILL_ANG or abs(p.v) > STILL_V for p in samples
    )
    seen = _distinct(samples)
    link = pace.link(ctx.config)
    stalled = spread[1] - (ctx.config.reply_time or 0.0) * ctx.config.time_scale  # beyond the link's reply time
    if not moved and held_for is not None and stalled >= held_for:
        why = (
            f"the target answered a pose {spread[1]:.2f} simulated s after it was asked, {stalled:.2f} s more than "
            f"the link takes and longer than the {held_for:g} s {name} was held: it did not run meanwhile (a loaded "
            f"machine; {link})"
        )
        return Held(seen, st, why, stale=True)
    if moved and len(seen) < DISTINCT:
        why = (
            f"{len(samples)} poses read, only {len(seen)} distinct: the target answered in bursts (it fell behind "
            f"the requests: a loaded machine or a slow target), its motion was not sampled while {name} was resent "
            f"({link})"
        )
        return Held(seen, st, why, stale=True)
    if moved and limit is not None and worst_gap >= 0.8 * limit:
        why = (
            f"the suite resent {name} {worst_gap:.2f} simulated s apart at worst, against the target's watchdog of "
            f"{limit:.2f} s: the machine ran the suite late, the watchdog may have stopped the platform ({link})"
        )
        return Held(seen, st, why)
    if moved and limit is not None and spread[1] - spread[0] >= 0.8 * limit:
        why = (
            f"the target's poses came {spread[0]:.2f} to {spread[1]:.2f} simulated s after they were asked: its "
            f"commands may have come as unevenly, and its watchdog of {limit:.2f} s may have stopped the platform "
            f"between two of them (a loaded machine or a jittery link; {link})"
        )
        return Held(seen, st, why)
    return Held(seen, st)


def settled(samples: list[Pose], n: int = 4) -> Pose:
    """The median velocities of the last ``n`` samples (one late sample of a loaded machine does not decide)."""
    last = samples[-n:]
    v = sorted(p.v for p in last)[len(last) // 2]
    w = sorted(p.w for p in last)[len(last) // 2]
    return Pose(last[-1].x, last[-1].y, last[-1].th, v, w)


def _vel_near(value: float, want: float) -> bool:
    return abs(value - want) <= 0.15 * abs(want) + 30.0


def _rot_near(value: float, want: float) -> bool:
    return abs(value - want) <= 0.15 * abs(want) + 0.03


_NEAR: dict[str, Callable[[float, float], bool]] = {"v": _vel_near, "w": _rot_near}
_STILL = {"v": STILL_V, "w": STILL_W}


def _dist_wheels(ctx: CaseContext) -> float | None:
    reply = ctx.get("CMD_GET_PLTF_PARAM_VEC")
    for p in reply.parameters:  # type: ignore[attr-defined]
        if p.key == "DistWheels":
            return reported.number(p.value, "the parameter DistWheels [mm]", lo=1.0, hi=100_000.0)
    return None


def track(ctx: CaseContext, until: Callable[[Pose], bool], within: float, period: float = 0.1) -> Pose:
    """``ctx.poll`` of the pose: the first that satisfies ``until`` within ``within`` simulated s, else the last.
    Where the target's measured reply time is longer than ``context.PACED`` simulated s (a slow link, issue 17) and
    it answers pipelined requests in order (erratum E-WIRE-008), a CMD_GET_POSITION leaves every ``period``
    without waiting for the replies before it, which are read as they come: the sampling keeps to the platform's
    time, not to the link's (one command against a watchdog of a simulated second or two was over before a
    second pose came back through a link of 200 ms at time scale 10)."""
    if not ctx.link_paced():
        return ctx.poll(lambda: pose(ctx), until, within=within)
    session = ctx.session()
    ask = [build("request", "CMD_GET_POSITION")]
    deadline = time.monotonic() + ctx.wall(within)
    asked, last = 0, None
    while True:
        if time.monotonic() < deadline:
            asked += session.send_pipelined(ask)
        while asked and (session.pending() or time.monotonic() >= deadline):
            last, asked = _pose_of(session.next_reply()), asked - 1
            if until(last):
                session.exchange([])  # the replies still due are read and dropped: never a later sample
                return last
        if time.monotonic() >= deadline and not asked:
            assert last is not None  # one was asked before the deadline, and read after it
            return last
        ctx.sleep(period)


def _set_moving(start: Pose) -> Callable[[Pose], bool]:
    return lambda q: abs(q.v) > 50 or q.dist(start) > MOVED


def set_moving(ctx: CaseContext, start: Pose, within: float = 2.0) -> tuple[bool, Pose]:
    """Whether a pose showed the platform moving since ``start`` (faster than 50 mm/s, or ``MOVED`` away) within
    ``within`` simulated s of a command, and that pose (else the last one read). A platform that shows nothing in
    that window gets a second one counted from the window's last reply: one reply that came late (a loaded
    machine stalled the target or the link for longer than the window) ends a window with one pose, the one asked
    right after the command, before the platform could move (issue 32: "did not set the platform moving" with one
    pose at the start, through a 100 ms accept loop at time scale 10 beside a CPU hog). A target that does not
    move shows nothing in either window."""
    moving = _set_moving(start)
    p = track(ctx, moving, within=within)
    if not moving(p):
        p = track(ctx, moving, within=within)
    return moving(p), p
