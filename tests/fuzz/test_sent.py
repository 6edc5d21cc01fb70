"""What the target was sent, in send order (fuzz/sent.py): the frames of flights whose writes interleaved, cut
into sessions that replay one after the other.

The campaign test puts the planted bug crash-after-start (zoo/bugs.py: a path move while the process-wide view of
the platform is in Running) between two real flights on the two ports of one instance: the first sends CONNECT,
INIT and START, the second a MOVE_ABS, then the first a STOP. That kills the instance; replayed one whole session
after the other (either order) it does not, replayed as the segments of ``sent`` it kills a fresh one.
"""

from __future__ import annotations

import sys
import time

import pytest

from pltf.fuzz import case
from pltf.fuzz.case import Delivery
from pltf.fuzz.flight import Flight, fly, step_flights
from pltf.fuzz.sent import segments
from pltf.fuzz.target import GET_STATUS, LEAD, Session, play_admitted
from pltf.harness.launch import Launcher
from pltf.spec.codec import REQUESTS, encode
from pltf.spec.model import enum_classes
from tests.emulator_gate import emulator_or_skip

CRASH = f"{sys.executable} -m pltf.zoo crash-after-start --serve emulator --ports {{ports}}"
CONNECT, INIT, START, STOP = (
    encode(REQUESTS[n]()) for n in ("CMD_CONNECT_TO_PLTF", "CMD_INIT_PLTF", "CMD_START", "CMD_STOP")
)
MOVE = encode(REQUESTS.CMD_MOVE_ABS(x=1000, y=0, angle=0))
RUNNING = enum_classes()["OperationState"].ST_OP_RUNNING
A, B = [1, 2, 3], [4, 5]  # frames as numbers: what goes where is all that counts below


def frames(*ids: int) -> list[bytes]:
    return [bytes([i]) * 3 for i in ids]


def test_frames_are_cut_where_another_flights_write_came_between() -> None:
    a = Session([LEAD, *frames(*A)], led=True)
    b = Session([LEAD, *frames(*B)], led=True)
    lead = len(LEAD)
    # a's first write carries its lead and frame 1, b's all of b, a's second write the rest of a
    got = segments([(a, a.data, [(0, lead + 3), (2, len(a.data))]), (b, b.data, [(1, len(b.data))])])
    assert [s.frames for s in got] == [[LEAD, *frames(1)], [LEAD, *frames(4, 5)], [LEAD, *frames(2, 3)]]
    assert all(s.led and s.half_close and not s.sync for s in got)


def test_a_frame_never_sent_whole_is_left_out_and_a_sync_status_is_kept() -> None:
    a = Session([LEAD, *frames(*A)], led=True, sync=True)
    data = a.data + GET_STATUS  # the flight appends its sync
    got = segments([(a, data, [(0, len(LEAD) + 4), (1, len(data))])])  # frame 2 cut by the first write
    assert [s.frames for s in got] == [[LEAD, *frames(1, 2, 3), GET_STATUS]]
    lead_only = Session([LEAD], led=True)
    assert segments([(lead_only, lead_only.data, [(0, len(LEAD))])]) == []
    cut = segments([(a, data, [(0, len(LEAD) + 4)])])  # the rest never went out
    assert [s.frames for s in cut] == [[LEAD, *frames(1)]]


def running(port: int) -> bool:
    """Whether the instance says it is in Running (GET_STATUS on a connection of its own)."""
    out, _ = play_admitted("127.0.0.1", port, Session([GET_STATUS], half_close=True), 2.0, 2.0)
    return any(getattr(r, "operation_state", None) == RUNNING for r in out.replies)


def died(target: Launcher, within: float) -> bool:
    """Whether the instance ended with the planted crash's status (134) within ``within`` s."""
    end = time.monotonic() + within
    while target.proc is not None and target.proc.poll() is None and time.monotonic() < end:
        time.sleep(0.02)
    return target.proc is not None and target.proc.poll() == 134


def replay_kills_a_fresh_instance(sessions: list[Session], within: float) -> bool:
    target = Launcher(CRASH, "127.0.0.1", 0, 0)
    port, _ = target.start()
    try:
        for s in sessions:
            play_admitted("127.0.0.1", port, s, 5.0, 5.0, alive=target.alive)
            if not target.alive():
                break
        return died(target, within)
    finally:
        target.cleanup()


def test_a_death_two_lanes_reached_together_replays_in_send_order(monkeypatch: pytest.MonkeyPatch) -> None:
    emulator_or_skip()
    monkeypatch.setattr(case, "MAX_PAUSE_TOTAL", 10.0)  # a slow case's pause is capped at 50 ms; here it is 3 s
    tail = [STOP, LEAD, LEAD, LEAD]  # the same length as the head: the slow delivery cuts in the middle
    first = Session([LEAD, CONNECT, INIT, START, *tail], Delivery("slow", 2, 3.0), half_close=True, led=True)
    assert len(first.data) // 2 == len(LEAD + CONNECT + INIT + START)
    second = Session([LEAD, MOVE], half_close=True, led=True)
    target = Launcher(CRASH, "127.0.0.1", 0, 0)
    port, other = target.start()
    try:
        a = Flight("127.0.0.1", port, first, 5.0)  # its first piece goes out at once, the STOP 3 s later
        end = time.monotonic() + 2.5  # the relay read the START before the move comes in on the other port: the
        while not running(other) and time.monotonic() < end:  # emulator behind it is in Running (a loaded machine)
            step_flights([a], until=time.monotonic() + 0.05)
        assert not a.done, ("the first flight ended before the emulator reported Running", a.out)
        b = Flight("127.0.0.1", other, second, 5.0)
        fly([a, b])
        assert died(target, 5.0)  # the two lanes together killed it
    finally:
        target.cleanup()
    assert not replay_kills_a_fresh_instance([first, second], 0.5)
    assert not replay_kills_a_fresh_instance([second, first], 0.5)
    sent = segments([(f.session, f.data, f.sends) for f in (a, b)])
    cut = [s.frames[1:] for s in sent]  # the STOP and its tail went out only if the instance lived 3 s more
    assert cut in ([[CONNECT, INIT, START], [MOVE]], [[CONNECT, INIT, START], [MOVE], tail]), cut
    assert replay_kills_a_fresh_instance(sent, 5.0)
