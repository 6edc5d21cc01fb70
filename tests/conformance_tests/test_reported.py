"""The sanitising step (conformance_tests/reported.py): what a target reports is judged, never used blindly."""

from __future__ import annotations

import math

import pytest

from pltf.conformance_tests import reported
from pltf.conformance_tests.outcome import Absurd
from pltf.spec.codec import build
from tests.conformance_tests.relays import le_pose


def _position(**fields: float) -> object:
    values = {"x": 1000, "y": -2000, "angle": 0.5, "vel_trans": 0.0, "vel_rot": 0.0, **fields}
    return build("reply", "CMD_GET_POSITION", **values)


def test_a_plausible_pose_passes_as_it_is() -> None:
    reply = _position(angle=-7.0, vel_trans=-1500.0)  # unwrapped after a turn; reversing at 1.5 m/s
    assert reported.position(reply) is reply  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("fields", "seen"),
    [
        ({"angle": math.nan}, "an angle of nan rad (CMD_GET_POSITION.angle: not a number"),
        ({"vel_trans": math.inf}, "a translational velocity of inf mm/s (CMD_GET_POSITION.vel_trans: an infinity"),
        ({"vel_rot": -math.inf}, "a rotational velocity of -inf rad/s"),
        ({"x": 2**31 - 1}, "an x coordinate of 2.14748e+09 mm (CMD_GET_POSITION.x: beyond"),
        ({"y": -(2**31)}, "a y coordinate of -2.14748e+09 mm"),
    ],
)
def test_an_absurd_value_ends_the_case_naming_it(fields: dict[str, float], seen: str) -> None:
    with pytest.raises(Absurd, match=f"^the target reported {seen.replace('(', '.').replace('+', '.')}"):
        reported.position(_position(**fields))  # type: ignore[arg-type]


def test_the_pose_written_little_endian_is_named_with_its_angle() -> None:
    """The issue's relay: a platform turned by 30 degrees reports an angle of about 1e85 rad."""
    reply = le_pose(_position(angle=math.radians(30)))  # type: ignore[arg-type]
    with pytest.raises(Absurd, match=r"the target reported an angle of [-0-9.]+e\+\d+ rad \(CMD_GET_POSITION\.angle"):
        reported.position(reply)


@pytest.mark.parametrize("text", ["abc", "nan", "inf", "1e400", "-5", ""])
def test_a_parameter_that_is_no_number_in_range_is_named(text: str) -> None:
    with pytest.raises(Absurd, match=f"the parameter VelWatchdogTime .ms. = {text!r}, not a number within"):
        reported.number(text, "the parameter VelWatchdogTime [ms]", lo=0.0, hi=3_600_000.0)


def test_a_parameter_that_is_a_number_is_read() -> None:
    assert reported.number(" 500 ", "x", lo=0.0) == 500.0
