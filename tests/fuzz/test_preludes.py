"""preludes: the state a unit is fuzzed in - paths over the chart, the plan, batches with chart commands last."""

from __future__ import annotations

import pytest

from pltf.fuzz import preludes, safety
from pltf.fuzz.case import Case
from pltf.fuzz.preludes import DOCUMENT_RESET, HARVEST, OP, StatePlan, chart_last, full, path
from pltf.spec.codec import REQUESTS, decode_frame, encode

ANY = frozenset[int]()


def names(frames: list[bytes]) -> list[str]:
    out = []
    for f in frames:
        t = decode_frame(f, "request")
        out.append(f"{t.NAME}({t.mode})" if t.NAME == "CMD_SET_MODE" else t.NAME)  # type: ignore[attr-defined]
    return out


@pytest.mark.parametrize(
    ("state", "mode", "target", "expected"),
    [
        (
            None,
            None,
            ("running", 3),
            ["CMD_STOP", "CMD_SHUTDOWN_PLTF", "CMD_CONNECT_TO_PLTF", "CMD_INIT_PLTF", "CMD_SET_MODE(3)", "CMD_START"],
        ),  # unknown: from anywhere
        (
            OP.ST_OP_NOT_INITIALIZED,
            0,
            ("running", 3),
            ["CMD_CONNECT_TO_PLTF", "CMD_INIT_PLTF", "CMD_SET_MODE(3)", "CMD_START"],
        ),
        (OP.ST_OP_RUNNING, 3, ("running", 3), []),  # there already
        (OP.ST_OP_RUNNING, 2, ("running", 3), ["CMD_STOP", "CMD_SET_MODE(3)", "CMD_START"]),  # another mode
        (OP.ST_OP_BREAKED, 3, ("running", 3), ["CMD_CONTINUE"]),
        (OP.ST_OP_RUNNING, 3, ("breaked", 3), ["CMD_BREAK"]),
        (OP.ST_OP_READY, 1, ("ready", 4), ["CMD_SET_MODE(4)"]),
        (OP.ST_OP_READY, 1, ("connected", None), ["CMD_SHUTDOWN_PLTF", "CMD_CONNECT_TO_PLTF"]),
        (OP.ST_OP_RUNNING, 1, ("not_connected", None), ["CMD_SHUTDOWN_PLTF"]),
    ],
)
def test_the_shortest_way_over_the_chart(
    state: int | None, mode: int | None, target: tuple[str, int | None], expected: list[str]
) -> None:
    assert names(path(state, mode, target, ANY)) == expected


def test_without_motion_no_path_starts_the_platform() -> None:
    forbidden = safety.forbidden(allow_motion=False)
    for state in (None, OP.ST_OP_NOT_INITIALIZED, OP.ST_OP_READY, OP.ST_OP_RUNNING, OP.ST_OP_BREAKED):
        for target in StatePlan(allow_motion=False).targets:
            frames = path(state, 0, target, forbidden)
            assert not {f[8] for f in frames} & forbidden, (state, target)


def test_the_full_prelude_reaches_a_state_from_anywhere() -> None:
    assert names(full(("breaked", 2))) == [
        "CMD_STOP",
        "CMD_SHUTDOWN_PLTF",
        "CMD_CONNECT_TO_PLTF",
        "CMD_INIT_PLTF",
        "CMD_SET_MODE(2)",
        "CMD_START",
        "CMD_BREAK",
    ]
    assert names(full(("not_connected", None))) == ["CMD_STOP", "CMD_SHUTDOWN_PLTF"]


def test_chart_commands_go_last_in_a_batch_and_the_rest_keeps_its_order() -> None:
    def case(name: str, **fields: object) -> Case:
        return Case((encode(REQUESTS[name](**fields)),), "gen.boundary", name)

    cases = [
        case("CMD_STOP"),
        case("CMD_MOVE_REL", x=1, y=2, angle=3),
        case("CMD_SHUTDOWN_PLTF"),
        case("CMD_GET_POSITION"),
        case("CMD_SET_MODE", mode=1),
    ]
    assert [c.telegram for c in chart_last(cases)] == [
        "CMD_MOVE_REL",
        "CMD_GET_POSITION",
        "CMD_STOP",
        "CMD_SHUTDOWN_PLTF",
        "CMD_SET_MODE",
    ]


def test_the_plan_visits_every_state_and_resets_the_documents_at_each_switch() -> None:
    plan = StatePlan(allow_motion=True)
    assert {name for name, _ in plan.targets} == {"not_connected", "connected", "ready", "running", "breaked"}
    first = plan.prelude(None, None, ANY)
    assert first[: len(DOCUMENT_RESET)] == DOCUMENT_RESET and HARVEST[0] in first  # the first: documents, harvest
    assert plan.prelude(None, None, ANY) == full(plan.current)  # then only the way there
    for _ in range(preludes.WINDOWS_PER_STATE):
        assert plan.current == ("not_connected", None)
        plan.window_done(huge=False)
    assert plan.current == ("connected", None) and plan.documents_due
    plan.prelude(OP.ST_OP_NOT_INITIALIZED, 0, ANY)
    plan.window_done(huge=True)  # a case over 1 MiB: its document may be active now
    assert plan.documents_due
    assert plan.check(("ready", 2), OP.ST_OP_READY, 2) and ("ready", 2) in plan.reached
    assert not plan.check(("ready", 2), OP.ST_OP_READY, 1)
