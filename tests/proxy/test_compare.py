"""proxy/compare.py: replies compared field by field by the volatile-field table, differences named."""

from __future__ import annotations

from typing import Any

from pltf.conformance_tests.readings import canonical
from pltf.proxy.compare import FieldDiff, diff_telegrams
from pltf.spec.codec import build, decode_frame, encode

STATUS: Any = canonical("CMD_GET_STATUS", {})


def reply(telegram: str, /, **fields: Any) -> Any:
    """A reply as it comes off the wire (group items as their named tuples)."""
    return decode_frame(encode(build("reply", telegram, **fields)), "reply")


def test_the_same_reply_has_no_difference_and_volatile_fields_are_ignored() -> None:
    assert diff_telegrams(STATUS, STATUS) == []
    noisy = STATUS.replace(timestamp=STATUS.timestamp + 999, cov_major=77, us_distance=(5,) * 16)
    assert diff_telegrams(STATUS, noisy) == []


def test_tolerances_and_enum_names() -> None:
    assert diff_telegrams(STATUS, STATUS.replace(est_x=STATUS.est_x + 30)) == []
    assert diff_telegrams(STATUS, STATUS.replace(est_x=STATUS.est_x + 31)) == [
        FieldDiff("est_x", str(STATUS.est_x), str(STATUS.est_x + 31))
    ]
    (d,) = diff_telegrams(STATUS.replace(motion_mode=4), STATUS.replace(motion_mode=3))
    assert d == FieldDiff("motion_mode", "MODE_MOTION_AUTOMATIC (4)", "MODE_MOTION_VEL (3)")


def test_groups_arrays_and_strings() -> None:
    a = reply("CMD_GET_PLTF_PARAM_VEC", parameters=(("IpoTransVel", "1000", 2, 1, 50, 1500),))
    b = reply("CMD_GET_PLTF_PARAM_VEC", parameters=(("IpoTransVel", "800", 2, 1, 50, 1500),))
    assert diff_telegrams(a, b) == [FieldDiff("parameters[0].value", "'1000'", "'800'")]
    assert diff_telegrams(a, a.replace(parameters=())) == [FieldDiff("parameters (count)", "1", "0")]
    m = reply("CMD_GET_MAP", xml="<map>" + "x" * 200 + "</map>", name="office")
    (d,) = diff_telegrams(m, m.replace(xml="<map>" + "x" * 150 + "y" + "x" * 49 + "</map>"))
    assert d.path == "xml" and "differs at 155" in d.recorded
    c = reply("CMD_GET_CAN_MESSAGES", messages=((1.0, 385, (1, 2, 3, 4, 5, 6, 7, 8)),))
    assert diff_telegrams(c, c.replace(messages=())) == []  # messages: volatile (the target's own boards)


def test_another_telegram_is_one_difference() -> None:
    pos = reply("CMD_GET_POSITION", x=0, y=0, angle=0.0, vel_trans=0.0, vel_rot=0.0)
    assert diff_telegrams(STATUS, pos) == [FieldDiff("(telegram)", "CMD_GET_STATUS", "CMD_GET_POSITION")]
    assert diff_telegrams(pos, pos.replace(angle=0.03)) == []  # 0.035 rad tolerance
    assert diff_telegrams(pos, pos.replace(angle=0.04)) == [FieldDiff("angle", "0.0", "0.04")]
