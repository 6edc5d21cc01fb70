"""The one sanitising step between what a target reports and what a case computes or builds from it (issue 32).

Rules:
- A case never turns target data into a harness error. Every value a case takes from a reply to do arithmetic
  with or to build a request from - the pose and velocities of CMD_GET_POSITION, a parameter read as a number -
  passes ``position`` or ``number`` first.
- A value outside its plausible domain (erratum E-WIRE-009: not a number, an infinity, or beyond the table's
  bound) ends the case with ``Absurd``, a FAIL whatever the case's level, whose message names the field, the value
  and the unit as seen: "the target reported an angle of 3.8e+85 rad (CMD_GET_POSITION.angle; ...)".
- The domains are a table: for an INT field the wire type's range less the suite's own offsets (a case moves at
  most about 1.3 m from where the platform stands, so a reported x that leaves no room for them is absurd); for a
  DOUBLE field a bound far above any platform (a thousand turns, 100 m/s, 100 rad/s). What lies within is the
  cases' to judge, as before.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pltf.conformance_tests.outcome import Absurd
from pltf.spec.codec import REPLIES
from pltf.spec.telegram import Telegram, user_fields

INT_MAX = 2**31 - 1
ROOM = 1_000_000  # mm (1 km) a reported coordinate must leave for the suite's offsets within INT


@dataclass(frozen=True)
class Domain:
    what: str  # the quantity in plain words
    unit: str
    bound: float  # |value| <= bound


# erratum E-WIRE-009: the plausible domain of each reported value a case computes with
DOMAINS: dict[tuple[str, str], Domain] = {
    ("CMD_GET_POSITION", "x"): Domain("an x coordinate", "mm", INT_MAX - ROOM),
    ("CMD_GET_POSITION", "y"): Domain("a y coordinate", "mm", INT_MAX - ROOM),
    ("CMD_GET_POSITION", "angle"): Domain("an angle", "rad", 2000 * math.pi),  # a thousand turns, unwrapped
    ("CMD_GET_POSITION", "vel_trans"): Domain("a translational velocity", "mm/s", 100_000.0),
    ("CMD_GET_POSITION", "vel_rot"): Domain("a rotational velocity", "rad/s", 100.0),
}


def _fields(name: str) -> list[str]:
    return [f.name for f in user_fields(REPLIES[name].DEF.reply or ()) if (name, f.name) in DOMAINS]


def absurd(name: str, field: str, value: float) -> str:
    """'' when ``value`` of reply ``name``'s ``field`` is plausible; else what was seen, in plain words."""
    d = DOMAINS[(name, field)]
    if math.isfinite(value) and abs(value) <= d.bound:
        return ""
    why = "not a number" if math.isnan(value) else "an infinity" if math.isinf(value) else f"beyond {d.bound:.3g}"
    return f"the target reported {d.what} of {value:.6g} {d.unit} ({name}.{field}: {why}, erratum E-WIRE-009)"


def checked(reply: Telegram) -> Telegram:
    """``reply`` itself when every value of it in ``DOMAINS`` is plausible; else ``Absurd`` naming the first."""
    for field in _fields(reply.NAME):
        problem = absurd(reply.NAME, field, getattr(reply, field))
        if problem:
            raise Absurd(problem)
    return reply


def position(reply: Telegram) -> Telegram:
    """A CMD_GET_POSITION reply a case may compute with (see the module rules)."""
    return checked(reply)


def number(text: str, what: str, *, lo: float = -math.inf, hi: float = math.inf) -> float:
    """A parameter's value read as a number, ``what`` naming it ("the parameter VelWatchdogTime [ms]"); ``Absurd``
    when the text is no finite number within [lo, hi]."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and lo <= value <= hi):
        raise Absurd(f"the target reported {what} = {text[:40]!r}, not a number within [{lo:g}, {hi:g}]")
    return value
