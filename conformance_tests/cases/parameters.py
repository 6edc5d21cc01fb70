"""Guide 5.9 / 6.3 / 6.4: platform parameters - listed, read, written back, range and syntax refused.

Rules of this module: the suite changes only parameters whose change is harmless on a standing platform
(never Geometry, Ultrasonic or Collision: "used for safety purposes and therefore should not be changed");
the Surveillance switches (siren, flashlight, ...) are outputs and only change behind the safety gate. Every
value changed is restored by a finalizer. Values are compared as numbers, never as text (E-PAR-006).
"""

from __future__ import annotations

import math
from typing import Any

from pltf.conformance_tests.cases._common import no_unsolicited, param_table
from pltf.conformance_tests.catalogue import Level, Tier, case
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Fail, NotApplicable
from pltf.spec.codec import build
from pltf.spec.parameters import Category, DataType, Parameter, load_parameters
from pltf.spec.telegram import Telegram

SPEC = load_parameters()
_UNSAFE = {Category.GEOM, Category.USONIC, Category.COLLISION}
_PARAM_TEXT = 'guide 6.3 CMD_SET_PLTF_PARAM: "Change the value of a parameter."; 6.4 CMD_GET_PLTF_PARAM'


def _safe(names: list[str], *, outputs: bool = False) -> list[Parameter]:
    out = []
    for n in names:
        p = SPEC.get(n)
        if p is None or not p.writable or p.category in _UNSAFE:
            continue
        if (p.category is Category.SURVEILLANCE) != outputs:
            continue
        out.append(p)
    return out


def _number(text: str, data_type: int) -> float | None:
    """The value a text stands for under E-PAR-005/006 (None when it is not one)."""
    t = text.strip(" \t\r\n")
    if data_type == DataType.BOOLEAN:
        return {"true": 1.0, "1": 1.0, "false": 0.0, "0": 0.0}.get(t.lower())
    try:
        v = float(t)
    except ValueError:
        return None
    return v if math.isfinite(v) else None


def _value(ctx: CaseContext, key: str) -> str:
    return _checked(ctx.get("CMD_GET_PLTF_PARAM", key=key), key)


def _checked(reply: Telegram, key: str) -> str:
    """The value of a CMD_GET_PLTF_PARAM reply asked for ``key``."""
    if reply.key != key:  # type: ignore[attr-defined]
        raise Fail(f"CMD_GET_PLTF_PARAM({key!r}) answered for key {reply.key!r}")  # type: ignore[attr-defined]
    return reply.value  # type: ignore[attr-defined, no-any-return]


def _same(a: str, b: str, p: Parameter) -> bool:
    x, y = _number(a, p.type), _number(b, p.type)
    return x is not None and y is not None and math.isclose(x, y, rel_tol=1e-9, abs_tol=1e-12)


def _other_value(p: Parameter, current: str) -> str:
    v = _number(current, p.type)
    if p.type is DataType.BOOLEAN:
        return "false" if v else "true"
    if p.type is DataType.INTEGER:
        n = int(v or 0)
        return str(n + 1 if n + 1 <= p.maximum else n - 1)
    step = (p.maximum - p.minimum) / 7.0
    x = (v or 0.0) + step
    return repr(x if x <= p.maximum else (v or 0.0) - step)


@case(
    "5.9/parameters/guide-properties-listed",
    level=Level.SHOULD,
    errata=("E-PAR-001", "E-PAR-002"),
    requirement='guide 5.9 lists the properties of each tab and 6.4 CMD_GET_PLTF_PARAM_VEC "Request the list of '
    'all supported parameters": every property of 5.9 is listed, under its key (errata E-PAR-001 '
    "PlanningEnabled, E-PAR-002 IpoRotVel), category and data type",
    telegrams=("CMD_GET_PLTF_PARAM_VEC",),
)
def guide_properties_listed(ctx: CaseContext) -> None:
    table = param_table(ctx)
    missing, wrong = [], []
    for p in SPEC.values():
        if not p.source.startswith("guide 5.9") or p.category is Category.USONIC:
            continue
        if p.name not in table:
            alt = {"PlanningEnabled": ("Planning Enabled", "E-PAR-001"), "IpoRotVel": ("IpoRotvel", "E-PAR-002")}
            if p.name in alt and alt[p.name][0] in table:
                ctx.deviate(alt[p.name][1], 0, f"the key is {alt[p.name][0]!r}")
                continue
            missing.append(p.name)
            continue
        e = table[p.name]
        if e.category != p.category:
            wrong.append(f"{p.name}: category {e.category}, guide tab says {p.category.name}")
    if missing or wrong:
        raise Fail("; ".join(([f"not listed: {', '.join(missing)}"] if missing else []) + wrong))


@case(
    "5.9/parameters/errata-parameters",
    level=Level.MAY,
    errata=("E-PAR-024",),
    requirement="errata E-PAR-008/009/018..023: the parameters the project added (ultrasonic geometry, "
    "InfraRedEnabled, watchdog and acceleration limits) are listed (informative)",
    telegrams=("CMD_GET_PLTF_PARAM_VEC",),
)
def errata_parameters(ctx: CaseContext) -> None:
    table = param_table(ctx)
    missing = [p.name for p in SPEC.values() if p.name not in table]
    if missing:
        raise NotApplicable(f"{len(missing)} parameters of the project's table are not listed, e.g. {missing[:4]}")


@case(
    "6.4/CMD_GET_PLTF_PARAM_VEC/entries-well-formed",
    level=Level.SHOULD,
    errata=("E-PAR-006", "E-PAR-027"),
    requirement="guide 6.4 CMD_GET_PLTF_PARAM_VEC: each entry has a key, its value, category, data type and "
    "min/max; errata E-PAR-005/006/027: the value text reads as its data type (booleans as "
    "'true'/'false') and lies within min..max",
    telegrams=("CMD_GET_PLTF_PARAM_VEC",),
)
def entries_well_formed(ctx: CaseContext) -> None:
    problems = []
    for key, e in param_table(ctx).items():
        v = _number(e.value, e.data_type)
        if not key or v is None:
            problems.append(f"{key!r}: value {e.value!r} is not a {DataType(e.data_type).name}")
            continue
        if e.data_type == DataType.BOOLEAN and e.value not in ("true", "false"):
            ctx.deviate("E-PAR-027", 0 if e.value in ("1", "0") else 1, f"{key} is reported as {e.value!r}")
        if e.minimum > e.maximum:
            problems.append(f"{key}: min {e.minimum} > max {e.maximum}")
        elif e.data_type != DataType.BOOLEAN and not e.minimum <= v <= e.maximum:
            problems.append(f"{key}: value {e.value} outside its min..max {e.minimum}..{e.maximum}")
    if problems:
        raise Fail("; ".join(problems[:8]))


@case(
    "6.3/CMD_GET_PLTF_PARAM/every-parameter",
    tier=Tier.SMOKE,
    requirement='guide 6.3 CMD_GET_PLTF_PARAM: "Request the value of a single parameter" - for every key of '
    "CMD_GET_PLTF_PARAM_VEC the single reply carries the same key, value, category, type and bounds",
    telegrams=("CMD_GET_PLTF_PARAM", "CMD_GET_PLTF_PARAM_VEC"),
)
def every_parameter(ctx: CaseContext) -> None:
    table = param_table(ctx)
    if not table:
        raise Fail("CMD_GET_PLTF_PARAM_VEC lists no parameter")
    s = ctx.session()
    from pltf.spec.codec import build

    for key in table:  # pipelined: every request first, then every reply
        s.send(build("request", "CMD_GET_PLTF_PARAM", key=key))
    for key, e in table.items():
        got = s.read_reply("CMD_GET_PLTF_PARAM")
        if tuple(got) != tuple(e):
            raise Fail(f"CMD_GET_PLTF_PARAM({key!r}) = {tuple(got)} but the vector lists {tuple(e)}")


def _get(key: str) -> Telegram:
    return build("request", "CMD_GET_PLTF_PARAM", key=key)


def _put(key: str, value: str) -> Telegram:
    return build("request", "CMD_SET_PLTF_PARAM", key=key, value=value)


def _round_trip(ctx: CaseContext, params: list[Parameter]) -> None:
    table = param_table(ctx)
    chosen = [p for p in params if p.name in table]
    if not chosen:
        raise NotApplicable("the target lists none of the parameters the suite may change")
    olds = ctx.preserve_params([p.name for p in chosen])
    news = [_other_value(p, old) for p, old in zip(chosen, olds, strict=True)]
    # each parameter set, read, set back and read again, in this order; pipelined (erratum E-WIRE-008)
    items = [
        t
        for p, old, new in zip(chosen, olds, news, strict=True)
        for t in (_put(p.name, new), _get(p.name), _put(p.name, old), _get(p.name))
    ]
    replies = iter(ctx.exchange(items))
    for p, old, new in zip(chosen, olds, news, strict=True):
        got = _checked(next(replies), p.name)
        if not _same(got, new, p):
            raise Fail(f"{p.name}: set to {new!r}, read back {got!r}")
        back = _checked(next(replies), p.name)
        if not _same(back, old, p):
            raise Fail(f"{p.name}: set back to {old!r}, read back {back!r}")


@case(
    "6.3/CMD_SET_PLTF_PARAM/round-trip",
    tier=Tier.SMOKE,
    requirement=_PARAM_TEXT + " - every writable "
    "parameter that is safe to change on a standing platform reads back what was set, and then its old value",
    telegrams=("CMD_SET_PLTF_PARAM", "CMD_GET_PLTF_PARAM"),
)
def round_trip(ctx: CaseContext) -> None:
    _round_trip(ctx, _safe(list(SPEC)))


@case(
    "6.3/CMD_SET_PLTF_PARAM/round-trip-surveillance",
    switches_outputs=True,
    requirement=_PARAM_TEXT + " - the Surveillance switches (flashlight, siren, PIR and radar sensors, "
    "surveillance mode) read back what was set",
    telegrams=("CMD_SET_PLTF_PARAM",),
)
def round_trip_outputs(ctx: CaseContext) -> None:
    _round_trip(ctx, _safe(list(SPEC), outputs=True))


def _refused(
    ctx: CaseContext,
    p: Parameter,
    text: str,
    what: str,
    erratum: str = "E-PAR-007",
    readings: dict[str, int] | None = None,
) -> None:
    """SET ``text`` must be refused with the old value kept; ``readings`` maps an observed value to the
    alternative of ``erratum`` it shows."""
    replies = ctx.exchange([_get(p.name), _put(p.name, text), _get(p.name)])  # pipelined (erratum E-WIRE-008)
    old, got = (_checked(r, p.name) for r in replies)
    if _same(got, old, p) and got == old:
        return
    ctx.send("CMD_SET_PLTF_PARAM", key=p.name, value=old)
    for value, index in (readings or {}).items():
        if _same(got, value, p):
            ctx.deviate(erratum, index, f"{p.name} = {text!r} ({what}) became {got!r}")
            return
    raise Fail(f"{p.name} = {text!r} ({what}): the old value {old!r} was not kept, it reads {got!r}", erratum=erratum)


@case(
    "6.3/CMD_SET_PLTF_PARAM/out-of-range-refused",
    errata=("E-PAR-007",),
    requirement="erratum E-PAR-007: a CMD_SET_PLTF_PARAM with a value outside the parameter's range is refused "
    "as a whole - the old value stays and a later GET shows it",
    telegrams=("CMD_SET_PLTF_PARAM", "CMD_GET_PLTF_PARAM"),
)
def out_of_range(ctx: CaseContext) -> None:
    table = param_table(ctx)
    numeric = [p for p in _safe(list(table)) if p.type is not DataType.BOOLEAN]
    if not numeric:
        raise NotApplicable("no numeric parameter the suite may change is listed")
    for p in numeric:
        ctx.preserve_param(p.name)
        above = p.maximum + 1 if p.type is DataType.INTEGER else p.maximum * 2 + 1
        below = p.minimum - 1 if p.type is DataType.INTEGER else p.minimum - abs(p.minimum) - 1
        for value, bound in ((above, p.maximum), (below, p.minimum)):
            text = str(value) if p.type is DataType.INTEGER else repr(float(value))
            _refused(ctx, p, text, "out of range", readings={str(bound): 0, text: 1})


@case(
    "6.3/CMD_SET_PLTF_PARAM/malformed-refused",
    errata=("E-PAR-006",),
    requirement="errata E-PAR-006/007: INTEGER is [+-]digits, DOUBLE a decimal number with '.' - any other text "
    "is refused and the old value stays",
    telegrams=("CMD_SET_PLTF_PARAM", "CMD_GET_PLTF_PARAM"),
)
def malformed(ctx: CaseContext) -> None:
    table = param_table(ctx)
    safe = _safe(list(table))
    ints = [p for p in safe if p.type is DataType.INTEGER]
    doubles = [p for p in safe if p.type is DataType.DOUBLE]
    if not ints and not doubles:
        raise NotApplicable("no numeric parameter the suite may change is listed")
    for p in ints[:1]:
        ctx.preserve_param(p.name)
        old = _value(ctx, p.name)
        for text in ("12abc", "", "0x10"):
            _refused(ctx, p, text, "not an integer", erratum="E-PAR-006")
        other = _other_value(p, old)  # a fraction of another value: truncation must not look like a refusal
        frac = f"{other}.7"
        _refused(ctx, p, frac, "a fraction", erratum="E-PAR-006", readings={other: 2})
    for p in doubles[:1]:
        ctx.preserve_param(p.name)
        old = _value(ctx, p.name)
        comma = _other_value(p, old).replace(".", ",")
        _refused(ctx, p, comma, "decimal comma", erratum="E-PAR-006", readings={comma.replace(",", "."): 1})
        for text in ("nan", "abc", "1e999"):
            _refused(ctx, p, text, "not a finite number", erratum="E-PAR-006")


@case(
    "6.3/CMD_SET_PLTF_PARAM/boolean-spellings",
    errata=("E-PAR-005",),
    requirement="erratum E-PAR-005: a server MUST accept lower-case true and false; the project also accepts 1/0 "
    "and any letter case, and refuses other words such as 'on' or 'maybe' (old value kept)",
    telegrams=("CMD_SET_PLTF_PARAM",),
)
def boolean_spellings(ctx: CaseContext) -> None:
    table = param_table(ctx)
    bools = [p for p in _safe(list(table)) if p.type is DataType.BOOLEAN]
    if not bools:
        raise NotApplicable("no BOOLEAN parameter the suite may change is listed")
    p = bools[0]
    ctx.preserve_param(p.name)
    must = (("true", "true"), ("false", "false"))
    may = (("TRUE", "true"), ("0", "false"), ("1", "true"), (" False ", "false"))
    # each spelling set and read back, in this order; pipelined (erratum E-WIRE-008)
    replies = ctx.exchange([t for text, _ in must + may for t in (_put(p.name, text), _get(p.name))])
    read = [(text, expected, _checked(r, p.name)) for (text, expected), r in zip(must + may, replies, strict=True)]
    for text, expected, got in read[: len(must)]:
        if not _same(got, expected, p):
            raise Fail(f"{p.name} = {text!r} reads back {got!r}")
    for text, expected, got in read[len(must) :]:
        if not _same(got, expected, p):
            ctx.deviate("E-PAR-005", 0, f"{p.name} = {text!r} was not taken (reads {got!r})")
    for text in ("maybe", "on"):
        _refused(ctx, p, text, "not a boolean word", erratum="E-PAR-005", readings={"false": 1})


@case(
    "6.3/CMD_SET_PLTF_PARAM/unknown-key",
    errata=("E-PAR-007",),
    requirement="erratum E-PAR-007: a CMD_SET_PLTF_PARAM with an unknown key is refused - no parameter appears or "
    "changes, and nothing is answered",
    telegrams=("CMD_SET_PLTF_PARAM", "CMD_GET_PLTF_PARAM_VEC"),
)
def unknown_key(ctx: CaseContext) -> None:
    before = param_table(ctx)
    ctx.send("CMD_SET_PLTF_PARAM", key="NoSuchParameterConformance", value="1")
    after = param_table(ctx)
    no_unsolicited(ctx, "CMD_SET_PLTF_PARAM")
    if set(after) != set(before):
        raise Fail(f"the parameter list changed: new keys {sorted(set(after) - set(before))}")
    changed = [k for k in before if tuple(after[k]) != tuple(before[k])]
    if changed:
        raise Fail(f"parameters changed: {changed[:5]}")


@case(
    "6.3/CMD_GET_PLTF_PARAM/exact-keys",
    errata=("E-PAR-003",),
    requirement="erratum E-PAR-003: keys are compared exactly (case-sensitive); a wrong-case key is unknown",
    telegrams=("CMD_GET_PLTF_PARAM",),
)
def exact_keys(ctx: CaseContext) -> None:
    table = param_table(ctx)
    key = next((k for k in table if k.lower() != k), None)
    if key is None:
        raise NotApplicable("no key with upper-case letters")
    reply = ctx.get("CMD_GET_PLTF_PARAM", key=key.lower())
    if reply.value and reply.value == table[key].value and reply.data_type == table[key].data_type:  # type: ignore[attr-defined]
        ctx.deviate("E-PAR-003", 0, f"{key.lower()!r} was answered like {key!r}")


@case(
    "6.3/CMD_SET_PLTF_PARAM/read-only-refused",
    errata=("E-PAR-024",),
    requirement="erratum E-PAR-024: the parameter-file values the project added (VelWatchdogTime, MaxTransVel, "
    "...) are read-only over the socket: a SET is refused and the value stays",
    telegrams=("CMD_SET_PLTF_PARAM", "CMD_GET_PLTF_PARAM"),
)
def read_only(ctx: CaseContext) -> None:
    table = param_table(ctx)
    ro = [p for p in SPEC.values() if not p.writable and p.name in table]
    if not ro:
        raise NotApplicable("none of the read-only parameters of the project's table is listed")
    olds = [_checked(r, p.name) for p, r in zip(ro, ctx.exchange([_get(p.name) for p in ro]), strict=True)]
    news = [_other_value(p, old) for p, old in zip(ro, olds, strict=True)]
    # each parameter set and read back, in this order; pipelined (erratum E-WIRE-008)
    replies = ctx.exchange([t for p, new in zip(ro, news, strict=True) for t in (_put(p.name, new), _get(p.name))])
    for p, old, new, r in zip(ro, olds, news, replies, strict=True):
        got = _checked(r, p.name)
        if not _same(got, old, p):
            ctx.send("CMD_SET_PLTF_PARAM", key=p.name, value=old)
            ctx.deviate("E-PAR-024", 1, f"{p.name} took {new!r}")


def expect_param(ctx: CaseContext, key: str, value: str, within: float) -> Any:
    """Poll CMD_GET_PLTF_PARAM until ``key`` reads ``value`` (used by the task program cases)."""
    p = SPEC[key]
    return ctx.poll(lambda: _value(ctx, key), lambda got: _same(got, value, p), within=within)
