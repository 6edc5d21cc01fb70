"""Differential mode: the reference server against a second instance of itself shows no difference;
a broken variant shows exactly where it differs; volatile fields are ignored or compared within tolerance."""

from __future__ import annotations

from pathlib import Path

import yaml

from pltf.conformance_tests.differential import compare, diff_replies, script, volatile
from pltf.conformance_tests.mutants.catalogue import BY_ID
from pltf.conformance_tests.mutants.proxy import FrameProxy
from pltf.conformance_tests.readings import canonical
from pltf.conformance_tests.target import Config
from pltf.harness import launch
from tests.emulator_gate import emulator_or_skip


def test_volatile_fields_are_ignored_and_tolerances_applied() -> None:
    a = canonical("CMD_GET_STATUS", {})
    assert diff_replies(0, "x", a, a.replace(timestamp=12345, est_x=25, us_distance=(5,) * 16)) == []
    (d,) = diff_replies(3, "CMD_GET_STATUS()", a, a.replace(est_x=31))
    assert (d.step, d.path, d.reference, d.target) == (3, "est_x", 0, 31)
    assert [x.path for x in diff_replies(0, "x", a, a.replace(operation_state=1))] == ["operation_state"]
    assert "CMD_GET_STATUS" in volatile() and "timestamp" in volatile()["CMD_GET_STATUS"]["ignore"]


def test_the_reference_agrees_with_itself_and_a_mutant_does_not() -> None:
    with launch.reference(time_scale=10.0) as ref, launch.reference(time_scale=10.0) as tgt:
        rc = Config("127.0.0.1", ref.ports[0], time_scale=10.0, simulator=True)
        tc = Config("127.0.0.1", tgt.ports[0], time_scale=10.0, simulator=True)
        assert compare(rc, tc, motion=True) == []
        assert len(script(True)) > 150
        with FrameProxy("127.0.0.1", tgt.ports, BY_ID["mode-not-reported"].make()) as proxy:
            diffs = compare(rc, Config("127.0.0.1", proxy.ports[0], time_scale=10.0), motion=False)
    assert diffs and {d.path for d in diffs} == {"motion_mode"}
    assert all(d.target == 0 and d.reference != 0 for d in diffs)


EMULATOR_DIFFERENCES = Path(__file__).resolve().parents[2] / "zoo" / "emulator_differences.yaml"


def test_the_reference_and_the_emulator_differ_exactly_where_documented() -> None:
    emulator_or_skip()
    documented = yaml.safe_load(EMULATOR_DIFFERENCES.read_text(encoding="utf-8"))
    with launch.reference(time_scale=10.0) as ref, launch.emulator(time_scale=10.0) as emu:
        rc = Config("127.0.0.1", ref.ports[0], time_scale=10.0, simulator=True, reply_timeout=10.0)
        ec = Config("127.0.0.1", emu.ports[0], time_scale=10.0, simulator=True, reply_timeout=10.0)
        diffs = compare(rc, ec, motion=True)
    named = {(d.request.split("(")[0], d.path) for d in diffs}
    assert named == {(e["reply"], e["field"]) for e in documented}
    for e in documented:
        seen = {(d.reference, d.target) for d in diffs if (d.request.split("(")[0], d.path) == (e["reply"], e["field"])}
        assert seen == {(e["reference"], e["emulator"])}, e["reply"]


def test_poses_are_compared_relative_to_the_start_of_the_session() -> None:
    import math

    from pltf.conformance_tests.differential import relative
    from pltf.spec.codec import REPLIES

    origin = (2000.0, 10000.0, math.pi / 2)  # standing at (2000, 10000), facing +y
    pos = REPLIES.CMD_GET_POSITION(x=2000, y=11000, angle=math.pi, vel_trans=0.0, vel_rot=0.0)
    rel = relative(pos, origin)
    assert (rel.x, rel.y) == (1000, 0) and abs(rel.angle - math.pi / 2) < 1e-9
    st = relative(canonical("CMD_GET_STATUS", {}).replace(est_x=2000, est_y=9500, est_angle=90000), origin)
    assert (st.est_x, st.est_y, st.est_angle) == (-500, 0, 0)
