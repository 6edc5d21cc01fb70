"""bugs.py: each planted bug fires on its input class only, and only behind its prelude of state (decided on the
requests alone, so a replay fires it again)."""

from __future__ import annotations

from typing import Any

from pltf.spec.codec import build, encode
from pltf.zoo.bugs import BUGS, CrashAfterStart, CrashInVelocityMode, HangOnUnknownKey, Leak, PlatformView
from pltf.zoo.frames import FrameCutter, Piece

AUTO, VEL, NO = 4, 3, 0


def req(name: str, **fields: Any) -> Piece:
    (piece,) = FrameCutter().feed(encode(build("request", name, **fields)))
    return piece


PRELUDE = [req("CMD_CONNECT_TO_PLTF"), req("CMD_INIT_PLTF"), req("CMD_START")]
MOVE = req("CMD_MOVE_REL", x=400, y=0, angle=0)


def feed(bug: Any, pieces: list[Piece]) -> list[Any]:
    return [bug.on_request(p, 0.0) for p in pieces]


def test_the_view_follows_the_chart_from_the_commands() -> None:
    v = PlatformView()
    for name in ("CMD_START", "CMD_INIT_PLTF"):  # not allowed before CONNECT: nothing changes
        v.on_request(name, req(name))
    assert v.state == "not connected"
    for name in ("CMD_CONNECT_TO_PLTF", "CMD_INIT_PLTF", "CMD_START", "CMD_BREAK", "CMD_CONTINUE", "CMD_STOP"):
        v.on_request(name, req(name))
    assert v.state == "ready"
    v.on_request("CMD_SET_MODE", req("CMD_SET_MODE", mode=AUTO))
    v.on_request("CMD_START", req("CMD_START"))
    v.on_request("CMD_SET_MODE", req("CMD_SET_MODE", mode=VEL))  # only in Ready: ignored in Running
    assert (v.state, v.mode) == ("running", AUTO)


def test_crash_after_start_needs_its_prelude() -> None:
    assert feed(CrashAfterStart(), [MOVE]) == [None]  # not running: the target refuses, no crash
    assert feed(CrashAfterStart(), [*PRELUDE[1:], MOVE]) == [None, None, None]  # no CONNECT: never running
    faults = feed(CrashAfterStart(), [*PRELUDE, MOVE])
    assert faults[:3] == [None] * 3 and faults[3].kind == "crash" and "MODE_MOTION_NO" in faults[3].why
    auto = [PRELUDE[0], PRELUDE[1], req("CMD_SET_MODE", mode=AUTO), PRELUDE[2], MOVE]
    assert feed(CrashAfterStart(), auto) == [None] * 5  # mode Automatic takes path commands
    vel = [
        PRELUDE[0],
        PRELUDE[1],
        req("CMD_SET_MODE", mode=VEL),
        PRELUDE[2],
        req("CMD_MOVE_VEL", vel_trans=100, vel_rot=0),
    ]
    assert feed(CrashAfterStart(), vel) == [None] * 5  # a velocity command is not a path command


def test_hang_on_an_unknown_key_only() -> None:
    bug = HangOnUnknownKey()
    assert bug.on_request(req("CMD_SET_PLTF_PARAM", key="IpoTransVel", value="800"), 0.0) is None
    assert bug.on_request(req("CMD_GET_PLTF_PARAM", key="NoSuch"), 0.0) is None
    fault = bug.on_request(req("CMD_SET_PLTF_PARAM", key="NoSuch", value="1"), 0.0)
    assert fault is not None and fault.kind == "hang" and "NoSuch" in fault.why


def test_the_leak_grows_with_every_request_and_kills_at_its_limit() -> None:
    bug = Leak(kb=256, limit_mb=1)
    status = req("CMD_GET_STATUS")
    assert feed(bug, [status] * 3) == [None] * 3 and bug.leaked == 3 * 256 * 1024
    fault = bug.on_request(status, 0.0)
    assert fault is not None and fault.kind == "crash" and "4 requests" in fault.why


def test_crash_in_velocity_mode_needs_mode_vel_set_before_start() -> None:
    wheel = req("CMD_MOVE_VEL_WHEEL", vel_right=100, vel_left=-(1 << 30))
    vel = [PRELUDE[0], PRELUDE[1], req("CMD_SET_MODE", mode=VEL), PRELUDE[2]]
    faults = feed(CrashInVelocityMode(), [*vel, wheel])
    assert faults[:4] == [None] * 4 and faults[4].kind == "crash" and "MOVE_VEL_WHEEL" in faults[4].why
    assert feed(CrashInVelocityMode(), [*PRELUDE, wheel]) == [None] * 4  # mode NO: the target refuses it
    late = [*PRELUDE, req("CMD_SET_MODE", mode=VEL), wheel]  # SET_MODE only counts in Ready
    assert feed(CrashInVelocityMode(), late) == [None] * 5
    slow = req("CMD_MOVE_VEL_WHEEL", vel_right=100, vel_left=-(1 << 30) + 1)
    assert feed(CrashInVelocityMode(), [*vel, slow]) == [None] * 5  # just above the limit: no overflow


def test_every_bug_is_named() -> None:
    assert set(BUGS) == {"crash-after-start", "crash-in-velocity-mode", "hang-unknown-key", "leak"}
