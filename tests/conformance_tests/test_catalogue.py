"""The catalogue: stable ids tied to guide sections, requirements, levels, and coverage of the whole protocol."""

from __future__ import annotations

import pytest

from pltf.conformance_tests import chart
from pltf.conformance_tests.cases import GROUP_ORDER
from pltf.conformance_tests.catalogue import ID_PATTERN, SECTIONS, Level, Tier, load_all, matches, select
from pltf.conformance_tests.mutants.catalogue import MUTANTS
from pltf.spec.codec import REPLIES, REQUESTS
from pltf.spec.errata import load_errata

CASES = load_all()


def test_every_case_has_an_id_a_section_and_a_requirement() -> None:
    assert len(CASES) >= 150
    for c in CASES.values():
        assert ID_PATTERN.match(c.id), c.id
        assert c.section in SECTIONS, c.id
        assert len(c.requirement) > 30, c.id
        assert c.group in GROUP_ORDER, (c.id, c.group)


def test_a_case_governed_by_an_erratum_takes_its_level() -> None:
    errata = load_errata()
    assert CASES["6.1/ports/second-client-turned-away"].level == errata["E-WIRE-007"].level == "SHOULD"
    assert CASES["6.2/framing/huge-length"].level == Level(errata["E-WIRE-004"].level)


def test_the_catalogue_covers_every_telegram_and_every_chart_cell() -> None:
    named = {t for c in CASES.values() for t in c.telegrams}
    assert {cls.NAME for cls in REQUESTS} <= named
    for cls in REPLIES:
        if cls.DEF.answered:
            assert f"6.4/{cls.NAME}/strict-decode" in CASES
    for state, command, _ in chart.every_transition():
        assert f"6.3/{command}/in-{state.value}" in CASES


def test_cells_the_guide_states_are_must_and_decisions_take_their_errata_level() -> None:
    assert CASES["6.3/CMD_SET_MODE/in-running"].level is Level.MUST
    assert CASES["6.3/CMD_SET_MODE/in-running"].errata == ()
    assert CASES["6.3/CMD_START/in-breaked"].level is Level.SHOULD
    assert CASES["6.3/CMD_START/in-breaked"].errata == ("E-SRV-018",)
    assert CASES["6.3/CMD_STOP/in-ready"].level is Level.MAY  # E-SRV-004 is a MAY


def test_every_chart_cell_is_stated_by_the_guide_or_decided_by_one_erratum() -> None:
    errata = load_errata()
    for state, command, _ in chart.every_transition():
        cell = (state, command)
        assert (cell in chart.GUIDE) != (cell in chart.DECIDED_BY), cell
        if cell in chart.DECIDED_BY:
            erratum = errata[chart.DECIDED_BY[cell]]
            assert command in erratum.applies_to, (cell, erratum.id)


def test_every_mutant_names_a_case_of_the_catalogue() -> None:
    assert len(MUTANTS) >= 20
    assert len({m.id for m in MUTANTS}) == len(MUTANTS)
    for m in MUTANTS:
        assert m.killer in CASES, m.id
        assert (m.wire is None) != (m.patch is None), m.id


@pytest.mark.parametrize(
    ("expr", "case_id", "hit"),
    [
        ("framing", "6.2/framing/coalesced", True),
        ("framing and not coalesced", "6.2/framing/coalesced", False),
        ("CMD_SET_MODE or CMD_START", "6.3/CMD_START/in-ready", True),
        ("6.3/CMD_SET_*/every-state", "6.3/CMD_SET_MAP/every-state", True),
        ("6.3/CMD_SET_*/every-state", "6.3/CMD_SET_MAP/round-trip", False),
        ("moves_platform", "4.3/MODE_MOTION_AUTOMATIC/move-abs", True),
        ("(should or may) and 6.2", "6.2/framing/bad-header", True),
    ],
)
def test_keyword_selection(expr: str, case_id: str, hit: bool) -> None:
    assert matches(CASES[case_id], expr) is hit


def test_bad_keyword_expression_is_refused() -> None:
    with pytest.raises(ValueError, match="bad -k"):
        matches(CASES["6.2/framing/coalesced"], "and or")


def test_selection_orders_by_group_and_puts_destructive_cases_last() -> None:
    chosen = select(CASES.values(), tier=Tier.EXHAUSTIVE)
    assert chosen[-1].destructive and chosen[-2].destructive
    groups = [c.group for c in chosen if not c.destructive]
    ranks = [GROUP_ORDER.index(g) for g in groups]
    assert ranks == sorted(ranks)
    smoke = select(CASES.values(), tier=Tier.SMOKE)
    assert 5 < len(smoke) < 30 and all(c.tier is Tier.SMOKE for c in smoke)
