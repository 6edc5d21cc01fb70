"""Differential mode: one scripted session against a reference server of our own and against the target, the
replies diffed field by field.

Rules:
- Both sides start from a known state: Ready in MODE_MOTION_NO. Poses are compared relative to each side's pose
  at the start of the session (``relative``), so targets standing in different places compare by what they
  did. With motion allowed the moves come first, on each side's own active map (the world a simulator moves
  in); then both sides get the suite's own map, roadmap and program (their documents are restored afterwards).
- The script is data (``script``): the chart walk with every GET_* request in every state, every motion mode,
  parameter reads and writes, documents; with motion allowed, relative moves in Automatic, each followed by a
  wait until the platform is at rest. Only the replies are compared; volatile fields (clocks, noise, sensor
  readings, values the guide leaves open) are ignored or compared within tolerances from ``spec/volatile.yaml``.
- A diff is (step, request, field path, reference value, target value). A report groups them by reply and field
  (``Differential.groups``): the same difference in every state of the chart walk is one line with a count, and a
  difference listed in zoo/emulator_differences.yaml is named as documented, with its reason and errata.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rich.console import Console

from pltf.conformance_tests import docdata
from pltf.conformance_tests.catalogue import Case, Level, Tier
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Outcome, Unreachable
from pltf.conformance_tests.poses import rest
from pltf.conformance_tests.reports.differential import Differential, print_differential
from pltf.conformance_tests.target import Config, Target
from pltf.harness import launch
from pltf.spec.model import enum_classes
from pltf.spec.telegram import Telegram
from pltf.spec.volatile import rule, values_differ, volatile

__all__ = [
    "Diff",
    "Differential",
    "Step",
    "compare",
    "diff_replies",
    "play",
    "relative",
    "run_differential",
    "script",
    "session",
    "volatile",
]
# The spec's enums are built at import; mypy sees them as plain IntEnum classes without members.
MotionMode: Any = enum_classes()["MotionMode"]


@dataclass(frozen=True)
class Step:
    kind: str  # "send", "get", "rest" (wait until the move's target is reached and the platform at rest), "state"
    name: str = ""
    fields: tuple[tuple[str, Any], ...] = ()

    def describe(self) -> str:
        args = ", ".join(f"{k}={v!r}"[:40] for k, v in self.fields)
        return f"{self.name}({args})" if self.kind in ("send", "get") else f"{self.kind} {self.name}"


def _get(telegram: str, /, **fields: Any) -> Step:
    return Step("get", telegram, tuple(fields.items()))


def _send(telegram: str, /, **fields: Any) -> Step:
    return Step("send", telegram, tuple(fields.items()))


GETS = (
    "CMD_GET_STATUS",
    "CMD_GET_POSITION",
    "CMD_GET_MAP",
    "CMD_GET_ROADMAP",
    "CMD_GET_PROGRAM",
    "CMD_GET_PLTF_PARAM_VEC",
    "CMD_GET_CAMERA",
    "CMD_GET_DEBUG_DATA",
)


def script(motion: bool) -> list[Step]:
    steps: list[Step] = []
    if motion:  # first, on each side's own map: the world a simulator moves in is its active map
        steps += [Step("state", St.RUNNING.value, (("mode", MotionMode.MODE_MOTION_AUTOMATIC),))]
        for x, y, a in ((400, 0, 0), (0, 0, 90000), (300, -200, -45000)):
            steps += [
                _send("CMD_MOVE_REL", x=x, y=y, angle=a),
                Step("rest"),
                _get("CMD_GET_POSITION"),
                _get("CMD_GET_STATUS"),
            ]
        steps += [_send("CMD_STOP"), _get("CMD_GET_STATUS")]
    steps.append(Step("documents"))  # from here on both sides hold the suite's documents
    for state in (St.NOT_CONNECTED, St.CONNECTED, St.READY, St.RUNNING, St.BREAKED):
        steps.append(Step("state", state.value))
        steps += [_get(g) for g in GETS]
        steps.append(_get("CMD_GET_CAN_MESSAGES", delete=0))
        steps.append(_get("CMD_GET_PLTF_PARAM", key="IpoTransVel"))
        for command in ("CMD_START", "CMD_STOP", "CMD_BREAK", "CMD_CONTINUE", "CMD_INIT_PLTF"):
            steps += [_send(command), _get("CMD_GET_STATUS")]
        steps.append(Step("state", state.value))
        steps += [_send("CMD_SET_MODE", mode=MotionMode.MODE_MOTION_VEL), _get("CMD_GET_STATUS")]
    steps.append(Step("state", St.READY.value))
    for mode in sorted(MotionMode._value2member_map_):
        steps += [_send("CMD_SET_MODE", mode=mode), _get("CMD_GET_STATUS")]
    steps += [_send("CMD_SET_MODE", mode=0)]
    for key, value in (
        ("IpoTransVel", "800"),
        ("IpoRotVel", "0.5"),
        ("EndTurnEnabled", "false"),
        ("IpoTransVel", "99999"),
        ("NoSuchParameter", "1"),
    ):
        steps += [_send("CMD_SET_PLTF_PARAM", key=key, value=value), _get("CMD_GET_PLTF_PARAM", key=key)]
    steps.append(_get("CMD_GET_PLTF_PARAM_VEC"))
    for kind in ("map", "roadmap"):
        up = kind.upper()
        steps += [
            _send(f"CMD_SET_{up}", name="diff", xml=docdata.variant(kind).decode()),
            _get(f"CMD_GET_{up}"),
            _send(f"CMD_SET_{up}", name="diff", xml=docdata.invalid(kind)[3][1].decode("latin-1")),
            _get(f"CMD_GET_{up}"),
        ]
    steps += [_send("CMD_SET_PROGRAM", xml=docdata.variant("program").decode()), _get("CMD_GET_PROGRAM")]
    return steps


def relative(reply: Telegram, origin: tuple[float, float, float]) -> Telegram:
    """Pose fields of ``reply`` in the frame of the session's start pose (x0, y0 mm, a0 rad), so that two
    targets that stand in different places are compared by what they did, not where they stood."""
    x0, y0, a0 = origin
    c, s = math.cos(-a0), math.sin(-a0)

    def xy(x: float, y: float) -> tuple[float, float]:
        return c * (x - x0) - s * (y - y0), s * (x - x0) + c * (y - y0)

    def wrap(a: float, full: float) -> float:
        return (a + full / 2) % full - full / 2

    if reply.NAME == "CMD_GET_POSITION":
        x, y = xy(reply.x, reply.y)  # type: ignore[attr-defined]
        return reply.replace(x=round(x), y=round(y), angle=wrap(reply.angle - a0, 2 * math.pi))  # type: ignore[attr-defined]
    if reply.NAME == "CMD_GET_STATUS":
        out = reply
        for p in ("est", "cmd"):
            x, y = xy(getattr(reply, f"{p}_x"), getattr(reply, f"{p}_y"))
            a = wrap(getattr(reply, f"{p}_angle") - math.degrees(a0) * 1000, 360000)
            out = out.replace(**{f"{p}_x": round(x), f"{p}_y": round(y), f"{p}_angle": round(a)})
        return out
    return reply


@dataclass(frozen=True)
class Diff:
    step: int
    request: str
    path: str
    reference: Any
    target: Any


def _is_group(value: Any) -> bool:
    return isinstance(value, tuple) and bool(value) and hasattr(value[0], "_fields")


def diff_replies(step: int, request: str, ref: Telegram, tgt: Telegram) -> list[Diff]:
    if ref.NAME != tgt.NAME:
        return [Diff(step, request, "(telegram)", ref.NAME, tgt.NAME)]
    out: list[Diff] = []
    for name, a, b in zip(ref._fields, ref, tgt, strict=True):
        r = rule(ref.NAME, name)
        if r.ignored:
            continue
        tol = r.tolerance
        if _is_group(a) or _is_group(b):
            if len(a) != len(b):
                out.append(Diff(step, request, f"{name} (count)", len(a), len(b)))
                continue
            for i, (ia, ib) in enumerate(zip(a, b, strict=True)):
                for sub, va, vb in zip(ia._fields, ia, ib, strict=True):
                    if values_differ(va, vb, tol):
                        out.append(Diff(step, request, f"{name}[{i}].{sub}", va, vb))
        elif name == "xml" and isinstance(a, str) and isinstance(b, str):
            if not docdata.same(a, b) and a != b:
                out.append(Diff(step, request, name, a[:60] + "...", b[:60] + "..."))
        elif values_differ(a, b, tol):
            out.append(Diff(step, request, name, a, b))
    return out


_CASE = Case(
    id="6.4/differential/session",
    func=lambda ctx: None,
    requirement="differential session",
    level=Level.MUST,
    tier=Tier.EXHAUSTIVE,
    group="replies",
)


def play(config: Config, steps: list[Step]) -> list[Telegram | None]:
    """Run ``steps`` against one side; the reply of every "get" step (None for the others)."""
    target = Target(config)
    ctx = CaseContext(target, _CASE)
    replies: list[Telegram | None] = []
    try:
        ctx.ready()
        for kind in ("map", "roadmap", "program"):
            ctx.preserve_document(kind)
        for key in ("IpoTransVel", "IpoRotVel", "EndTurnEnabled"):
            ctx.preserve_param(key)
        p0 = ctx.position()
        origin = (p0.x, p0.y, p0.angle)  # type: ignore[attr-defined]
        for step in steps:
            fields = dict(step.fields)
            if step.kind == "documents":
                for kind in ("map", "roadmap"):
                    ctx.send(f"CMD_SET_{kind.upper()}", name="diff", xml=docdata.valid(kind).decode())
                ctx.send("CMD_SET_PROGRAM", xml=docdata.valid("program").decode())
                replies.append(None)
            elif step.kind == "state":
                ctx.ensure(St(step.name) if step.name else St.READY, fields.get("mode", 0))
                replies.append(None)
            elif step.kind == "rest":
                ctx.sleep(0.5)  # the move has started by now
                # the move's end: its target reached (guide 6.4), not a pause between driving and the end turn
                ctx.poll(ctx.status, lambda s: bool(s.telegram.target_reached), within=30.0)  # type: ignore[attr-defined]  # a GET_STATUS field, from the spec
                rest(ctx, within=30.0)
                replies.append(None)
            elif step.kind == "send":
                ctx.send(step.name, **fields)
                replies.append(None)
            else:
                replies.append(relative(ctx.get(step.name, **fields), origin))
        ctx.ready()
    finally:
        ctx.finish()
        target.close()
    return replies


def compare(reference: Config, target: Config, motion: bool) -> list[Diff]:
    steps = script(motion)
    ref, tgt = play(reference, steps), play(target, steps)
    diffs: list[Diff] = []
    for i, (step, a, b) in enumerate(zip(steps, ref, tgt, strict=True)):
        if a is not None and b is not None:
            diffs += diff_replies(i, step.describe(), a, b)
    return diffs


def session(config: Config) -> Differential:
    """The differential session against a reference server started for it. A target that closes, stalls or
    garbles mid-session is the session's FAIL (``error``); one that cannot be reached is ``unreachable``."""
    steps = len(script(config.motion_allowed))
    try:
        with launch.reference(time_scale=config.time_scale) as ref:
            ref_config = Config("127.0.0.1", ref.ports[0], time_scale=config.time_scale, simulator=True)
            return Differential(steps, compare(ref_config, config, motion=config.motion_allowed))
    except Unreachable as exc:
        return Differential(steps, error=f"target unreachable: {exc}", unreachable=True)
    except (Outcome, OSError) as exc:
        return Differential(steps, error=str(exc))


def run_differential(config: Config, console: Console) -> int:
    """``pltf conform --differential``: 0 when the target answers like the reference server, else 1."""
    result = session(config)
    print_differential(result, console)
    return result.exit_code
