"""The volatile-field table: every entry names a real reply field; rules and tolerances as written."""

from __future__ import annotations

import math

from pltf.spec.volatile import EXACT, Rule, check_table, rule, values_differ


def test_every_entry_names_a_reply_field() -> None:
    assert check_table() == []


def test_rules() -> None:
    assert rule("CMD_GET_STATUS", "timestamp") == Rule(ignored=True)
    assert rule("CMD_GET_STATUS", "us_distance") == Rule(ignored=True)  # glob us_*
    assert rule("CMD_GET_STATUS", "cmd_x") == Rule(tolerance=30.0)
    assert rule("CMD_GET_STATUS", "operation_state") == EXACT
    assert rule("CMD_GET_PLTF_PARAM", "value") == EXACT  # no entry at all


def test_values_differ() -> None:
    assert not values_differ(100, 130, 30.0) and values_differ(100, 131, 30.0)
    assert values_differ(0.0, math.nan, 1.0) and values_differ(math.inf, math.inf, 1.0)
    assert values_differ(1, 2, None) and not values_differ("a", "a", 1.0) and values_differ("a", "b", 1.0)
