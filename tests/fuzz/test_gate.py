"""gate: one port as the fuzzer sees it - backoff, pipelining, dear connections (no sockets, no clock)."""

from __future__ import annotations

from pltf.fuzz.gate import BACKOFF_FIRST, BACKOFF_MAX, PIPELINE_TURN_AWAYS, Gate


def test_a_turned_away_client_waits_longer_each_time_and_starts_over_when_served() -> None:
    g = Gate(0, pipelining=True)
    g.ended(10.0, admitted=False, behind=False)
    assert g.backoff == BACKOFF_FIRST and not g.may_connect(10.0) and g.may_connect(10.0 + BACKOFF_FIRST)
    pauses = []
    for k in range(12):
        g.ended(11.0 + k, admitted=False, behind=False)
        pauses.append(g.backoff)
    assert pauses == sorted(pauses) and pauses[-1] == BACKOFF_MAX
    g.admitted(30.0, behind=False)
    assert g.backoff == 0.0
    g.ended(31.0, admitted=False, behind=False)
    assert g.backoff == BACKOFF_FIRST


def test_pipelining_stops_once_pipelined_newcomers_are_turned_away() -> None:
    g = Gate(1, pipelining=True)
    for _ in range(40):  # 3 of 40 pipelined units turned away: more than one in twenty
        g.connected(0.0, behind=True)
    for k in range(PIPELINE_TURN_AWAYS):
        assert g.pipelining
        g.ended(1.0 + k, admitted=False, behind=True)
    assert not g.pipelining
    g = Gate(1, pipelining=True)
    for _ in range(1000):  # a few turn-aways among many pipelined units: a hiccup, not the target's way
        g.connected(0.0, behind=True)
    for k in range(PIPELINE_TURN_AWAYS):
        g.ended(1.0 + k, admitted=False, behind=True)
    assert g.pipelining
    g.ended(5.0, admitted=False, behind=False)  # a client alone turned away says nothing about pipelining
    assert g.pipelining


def test_a_port_is_dear_when_fresh_clients_are_turned_away_before_they_are_served() -> None:
    slow, quick = Gate(0, True), Gate(1, True)
    t = 0.0
    for _ in range(8):
        slow.ended(t, admitted=True, behind=False)  # our client left at t ...
        slow.ended(t + 0.001, admitted=False, behind=False)  # ... the next one is turned away ...
        slow.admitted(t + 0.02, behind=False)  # ... and served 20 ms later
        quick.ended(t, admitted=True, behind=False)
        quick.admitted(t + 0.0001, behind=False)
        t += 1.0
    assert slow.dear and round(slow.release, 3) == 0.02
    assert not quick.dear and quick.release < 0.001
    assert not Gate(0, True).dear  # nothing known yet


def test_a_loaded_machine_makes_waits_long_but_not_a_port_dear() -> None:
    g = Gate(0, True)
    for k in range(10):
        g.ended(float(k), admitted=True, behind=False)
        g.admitted(k + 0.03, behind=False)  # 30 ms of our own delay (a busy CPU), never turned away
    assert g.release > 0.01 and not g.dear
