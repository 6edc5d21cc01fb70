"""Whatever a target reports, the suite judges it and never breaks itself (issue 32): replies with absurd values
(every numeric field at its wire type's extremes, NaN, the infinities) reach the cases through a relay in front of
the reference server, and no case ends in ERROR; the FAILs name what was seen."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pltf.conformance_tests import reported
from pltf.conformance_tests.catalogue import Tier, Verdict, load_all, select
from pltf.conformance_tests.runner import Runner, RunResult
from pltf.conformance_tests.target import Config
from pltf.harness import launch
from pltf.spec.codec import REPLIES
from pltf.spec.compiler import WIRE, value_range
from pltf.spec.model import FieldDef
from pltf.spec.strategies import _INT_BOUNDS
from pltf.spec.telegram import user_fields
from tests.conformance_tests.conftest import TIME_SCALE
from tests.conformance_tests.relays import ABSURD, Relay, Rewrite, fields_set

MAX = 1.7976931348623157e308
ABSURD_DOUBLES = (math.nan, math.inf, -math.inf, MAX, -MAX)


def extremes(f: FieldDef) -> st.SearchStrategy[float]:
    """The values at the edge of ``f``'s domain (spec/compiler.WIRE and the field's declared range): an INT's
    bounds, a DOUBLE's NaN, infinities and largest magnitudes."""
    char = WIRE[f.type][0]
    if char == "d":
        return st.sampled_from(ABSURD_DOUBLES)
    lo, hi = _INT_BOUNDS[char]
    declared = value_range(f)  # a field with a declared range (lookup_percent 0..99): its own extremes
    if declared is not None:
        lo, hi = max(lo, declared[0]), min(hi, declared[1])
    return st.sampled_from((lo, hi))


def numeric(name: str) -> dict[str, FieldDef]:
    return {
        f.name: f
        for f in user_fields(REPLIES[name].DEF.reply or ())
        if f.type in WIRE and not f.repeat and not f.enum and f.type != "BOOL"
    }


def replies(name: str, only: Callable[[FieldDef], bool] = lambda f: True) -> st.SearchStrategy[dict[str, float]]:
    """Some numeric fields of reply ``name`` (at least one), each at one of its extremes."""
    fields = {n: f for n, f in numeric(name).items() if only(f)}
    chosen = st.lists(st.sampled_from(sorted(fields)), min_size=1, max_size=len(fields), unique=True)
    return chosen.flatmap(lambda names: st.fixed_dictionaries({n: extremes(fields[n]) for n in names}))


def both(position: dict[str, float], status: dict[str, float]) -> Rewrite:
    pos, stat = fields_set("CMD_GET_POSITION", position), fields_set("CMD_GET_STATUS", status)
    return lambda reply: stat(pos(reply))


# cases that build requests from the reported pose (MOVE_ABS, SET_FRM_PLTF) or judge it; each reads it first
CHEAP = (
    "6.4/CMD_GET_POSITION/agrees-with-status",
    "6.3/CMD_SET_FRM_PLTF/sets-estimate",
    "4.3/MODE_MOTION_AUTOMATIC/move-abs",
    "4.3/MODE_MOTION_VEL/move-vel",
)


def _run(upstream: list[int], rewrite: Rewrite, ids: tuple[str, ...]) -> RunResult:
    with Relay(upstream, rewrite=rewrite) as relay:
        config = Config("127.0.0.1", relay.ports[0], relay.ports[1], time_scale=TIME_SCALE, simulator=True, reruns=0)
        cases = [load_all()[i] for i in ids]
        return Runner(config, cases).run()


def _errors(run: RunResult) -> list[str]:
    return [f"{r.case.id}: {r.message.splitlines()[0]}" for r in run.results if r.verdict is Verdict.ERROR]


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(position=replies("CMD_GET_POSITION"), status=replies("CMD_GET_STATUS", lambda f: f.type == "DOUBLE"))
def test_absurd_poses_end_in_fails_that_name_them(
    reference: launch.Launched, position: dict[str, float], status: dict[str, float]
) -> None:
    run = _run(reference.ports, both(position, status), CHEAP)
    assert not _errors(run), _errors(run)
    first = next(n for n in numeric("CMD_GET_POSITION") if n in position)  # the first absurd field the suite reads
    seen = reported.absurd("CMD_GET_POSITION", first, position[first])
    for r in run.results:
        assert r.verdict is Verdict.FAIL, (r.case.id, r.verdict, r.message)
        assert r.message == seen, (r.case.id, r.message)


@pytest.mark.slow
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(position=replies("CMD_GET_POSITION"), status=replies("CMD_GET_STATUS"))
def test_absurd_replies_never_end_a_motion_case_in_error(
    reference: launch.Launched, position: dict[str, float], status: dict[str, float]
) -> None:
    """Every numeric field of GET_STATUS too (an INT at its bounds is no absurd pose: the case goes on with it)."""
    motion = tuple(c.id for c in select(load_all().values(), tier=Tier.STANDARD) if c.moves_platform)
    run = _run(reference.ports, both(position, status), motion)
    assert not _errors(run), _errors(run)


@pytest.mark.slow
@pytest.mark.parametrize("absurd", sorted(ABSURD))
def test_pltf_conform_through_an_absurd_relay_exits_1_naming_the_values(absurd: str, tmp_path: Path) -> None:
    """The issue's acceptance: the standard tier with --allow-motion, through the relay, exits 1 with FAILs that
    name the values, and no case ends in ERROR."""
    rewrite = ABSURD[absurd]
    with launch.reference(time_scale=TIME_SCALE) as server, Relay(server.ports, rewrite=rewrite) as relay:
        cmd = [sys.executable, "-m", "pltf.cli.main", "conform", "--target", f"127.0.0.1:{relay.ports[0]}"]
        cmd += ["--second-port", str(relay.ports[1]), "--time-scale", str(TIME_SCALE), "--allow-motion"]
        cmd += ["--json", str(tmp_path / "report.json")]
        done = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=600)
    assert done.returncode == 1, done.stdout[-3000:] + done.stderr
    assert json.loads((tmp_path / "report.json").read_text())["counts"]["ERROR"] == 0  # exit 1, not 2, says it too
    assert "the target reported" in done.stdout and "erratum E-WIRE-009" in done.stdout
