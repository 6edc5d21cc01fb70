"""The client against the reference server the way an application drives it: several commands in a row, retries,
a goal next to the current pose, a goal that is refused (issue 22).

One reference server (``python -m pltf.reference_server --time-scale 5``, the office fixture) serves the module; each
scenario first brings the platform to Running in mode Automatic from wherever the one before left it, and
drives in the office's east-west corridor (y 8800..11200 mm) or to its north rooms. A loaded machine makes the
server catch up on its control periods in bursts (seconds of simulated time between two replies), so a goal
that must not be reached before the next command lies far away (FAR).
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Iterator

import pytest
from client_fakes import AUTOMATIC, READY, RUNNING, LiveServer

from pltf.client import (
    AsyncPlatformClient,
    CommandRejected,
    ConnectionClosed,
    PlatformClient,
    Pose,
    Status,
)

TOL_POS, TOL_ANGLE = 20.0, 2.0  # TargetReachedTolPos [mm], TargetReachedTolAngle [deg]: the defaults (E-PAR-021)
PILLAR = (3500, 16000)  # a pillar of fixtures/maps/office.map (r = 250 mm)
FAR = 25000  # mm: a corridor goal 20 m beyond where the scenarios turn back
TIME_SCALE = 5.0


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveServer]:
    root = tmp_path_factory.mktemp("scenarios")
    live = LiveServer(root / "data", root / "server.log", TIME_SCALE)
    try:
        yield live
    finally:
        live.close()


def prepare(pltf: PlatformClient) -> Status:
    """Running in mode Automatic, whatever the scenario before left."""
    status = pltf.bring_up(timeout=10)
    if status.motion_mode != AUTOMATIC:
        if status.operation_state != READY:
            pltf.stop()
            pltf.wait_state(READY, timeout=5)
        pltf.set_mode(AUTOMATIC)
        pltf.wait_mode(AUTOMATIC, timeout=5)
    if pltf.get_status().operation_state != RUNNING:
        pltf.start()
    return pltf.wait_state(RUNNING, timeout=5)


@pytest.fixture
def pltf(server: LiveServer) -> Iterator[PlatformClient]:
    with PlatformClient("127.0.0.1", server.ports[0], timeout=10) as client:
        prepare(client)
        yield client


def at(pose: Pose, x: float, y: float, angle: float | None = None, pos_tol: float = TOL_POS) -> bool:
    near = math.hypot(pose.x_mm - x, pose.y_mm - y) <= pos_tol
    return near and (angle is None or abs(turn(pose.angle_deg, angle)) <= TOL_ANGLE)


def turn(a: float, b: float) -> float:
    """Degrees from b to a, the short way round."""
    return (a - b + 180.0) % 360.0 - 180.0


def goto(pltf: PlatformClient, x: int, y: int, angle_mdeg: int) -> Status:
    pltf.move_abs(x_mm=x, y_mm=y, angle_mdeg=angle_mdeg)
    status = pltf.wait_target_reached(timeout=60)
    assert at(status.pose, x, y, angle_mdeg / 1000), status.pose
    return status


def test_a_refused_goal_then_a_reachable_one(pltf: PlatformClient) -> None:
    # issue 22, bug 1: the retry was reported refused by the refusal before it
    pltf.move_abs(x_mm=PILLAR[0], y_mm=PILLAR[1], angle_mdeg=0)
    with pytest.raises(CommandRejected, match="PLANNER_COLLISION_TARGET") as refused:
        pltf.wait_target_reached(timeout=20)
    assert refused.value.command == "CMD_MOVE_ABS"
    pltf.move_abs(x_mm=3000, y_mm=10200, angle_mdeg=0)
    status = pltf.wait_target_reached(timeout=60)
    assert status.target_reached and at(status.pose, 3000, 10200, 0), status.pose


def test_a_goal_replaced_while_driving(pltf: PlatformClient) -> None:
    goto(pltf, 2500, 10000, 0)
    pltf.move_abs(x_mm=FAR, y_mm=10000, angle_mdeg=0)
    driving = pltf.wait_until(lambda s: s.pose.x_mm > 3500, timeout=30, what="driving east")
    assert not driving.target_reached
    pltf.move_abs(x_mm=3000, y_mm=9800, angle_mdeg=180_000)  # guide 4.3: the new command preempts the old
    farthest = pltf.wait_until(lambda s: s.pose.x_mm < driving.pose.x_mm, timeout=30, what="turned back")
    status = pltf.wait_target_reached(timeout=60)
    assert at(status.pose, 3000, 9800, 180), status.pose
    assert farthest.pose.x_mm < FAR - 1000


def test_stop_while_driving(pltf: PlatformClient) -> None:
    goto(pltf, 2500, 10000, 0)
    pltf.move_abs(x_mm=FAR, y_mm=10000, angle_mdeg=0)
    pltf.wait_until(lambda s: s.pose.x_mm > 3500, timeout=30, what="driving east")
    pltf.stop()
    assert pltf.wait_state(READY, timeout=5).operation_state is READY
    with pytest.raises(CommandRejected, match="ST_OP_READY: the platform moves only in state Running"):
        pltf.wait_target_reached(timeout=5)
    still = pltf.wait_until(lambda s: pltf.get_position().vel_trans_mm_s == 0.0, timeout=10, what="standstill")
    assert still.pose.x_mm < FAR - 1000 and not still.target_reached
    time.sleep(2.0 / TIME_SCALE)  # two simulated seconds: it stays where it stopped
    assert abs(pltf.get_status().pose.x_mm - still.pose.x_mm) < 5
    prepare(pltf)
    goto(pltf, 3000, 10000, 0)  # and drives again after CMD_START


def _watch_while_waiting(port: int, move: tuple[int, int, int]) -> tuple[Status, list[Pose], float]:
    """MOVE_ABS, then the wait, with the pose sampled every 10 ms beside it on the same connection."""

    async def main() -> tuple[Status, list[Pose], float]:
        async with AsyncPlatformClient("127.0.0.1", port, timeout=10) as aio:
            poses: list[Pose] = []
            await aio.move_abs(*move)
            t0 = time.monotonic()
            wait = asyncio.ensure_future(aio.wait_target_reached(timeout=30, poll=0.01))
            while not wait.done():
                poses.append((await aio.get_status()).pose)
                await asyncio.sleep(0.01)
            return await wait, poses, time.monotonic() - t0

    return asyncio.run(main())


def test_a_goal_at_the_current_pose(pltf: PlatformClient, server: LiveServer) -> None:
    here = goto(pltf, 3500, 10500, 45_000)
    pltf.close()
    move = (round(here.est_x_mm), round(here.est_y_mm), here.est_angle_mdeg)
    status, poses, took = _watch_while_waiting(server.ports[0], move)
    assert status.target_reached and took < 2.0
    assert all(at(p, here.pose.x_mm, here.pose.y_mm, here.pose.angle_deg, pos_tol=5.0) for p in poses), poses


def test_a_goal_within_the_tolerances(pltf: PlatformClient, server: LiveServer) -> None:
    # issue 22, bug 2: 2 mm and 0.8 degrees away, the platform turned from 46 to 182 degrees and back
    here = goto(pltf, 3500, 10500, 45_000)
    pltf.close()
    move = (round(here.est_x_mm) - 2, round(here.est_y_mm), here.est_angle_mdeg - 800)
    status, poses, _ = _watch_while_waiting(server.ports[0], move)
    assert status.target_reached
    swing = max(abs(turn(p.angle_deg, here.pose.angle_deg)) for p in poses)
    moved = max(math.hypot(p.x_mm - here.pose.x_mm, p.y_mm - here.pose.y_mm) for p in poses)
    assert swing < 1.0 and moved < 5.0, (swing, moved)


def test_move_rel_after_move_abs(pltf: PlatformClient) -> None:
    start = goto(pltf, 3000, 10000, 0).pose
    pltf.move_rel(x_mm=1500, y_mm=0, angle_mdeg=90_000)  # 1.5 m ahead, then facing north
    status = pltf.wait_target_reached(timeout=60)
    a = math.radians(start.angle_deg)
    x, y = start.x_mm + 1500 * math.cos(a), start.y_mm + 1500 * math.sin(a)
    assert at(status.pose, x, y, start.angle_deg + 90), status.pose
    pltf.move_rel(x_mm=0, y_mm=0, angle_mdeg=-90_000)  # and back to the east, on the spot
    assert at(pltf.wait_target_reached(timeout=60).pose, x, y, start.angle_deg)


def test_a_wait_that_outlives_a_reconnect(pltf: PlatformClient, server: LiveServer) -> None:
    goto(pltf, 2500, 10000, 0)
    pltf.close()
    port = server.ports[0]

    async def main() -> Status:
        first = await AsyncPlatformClient.connect("127.0.0.1", port, timeout=10)
        await first.move_abs(FAR, 10000, 0)
        wait = asyncio.ensure_future(first.wait_target_reached(timeout=60))
        while (await first.get_status()).pose.x_mm < 3500:  # under way
            await asyncio.sleep(0.01)
        await first.close()  # the connection goes (a cable, a restart of the application)
        with pytest.raises(ConnectionClosed):
            await wait
        async with AsyncPlatformClient("127.0.0.1", port, timeout=10) as again:
            driving = await again.get_status()
            assert not driving.target_reached and driving.pose.x_mm < FAR - 500  # the platform drove on alone
            return await again.wait_target_reached(timeout=60)  # no move sent here: every status counts

    status = asyncio.run(main())
    assert at(status.pose, FAR, 10000, 0), status.pose
