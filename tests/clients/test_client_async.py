"""The asyncio client (clients/pltf_client/aio.py) against the FakePlatform of client_fakes.py and the
reference server. Each test runs its own event loop with ``asyncio.run`` (no plugin needed).
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Awaitable, Callable
from typing import Any

import pytest
from client_fakes import AUTOMATIC, CAPTURED, READY, RUNNING, FakePlatform, LiveServer

from pltf.client import (
    AsyncPlatformClient,
    CommandRejected,
    ConnectionClosed,
    MotionMode,
    OperationState,
    PlannerState,
    Position,
    ProtocolError,
    Status,
    Timeout,
)
from pltf.spec.codec import REQUESTS


def run_with_client(port: int, body: Callable[[AsyncPlatformClient], Awaitable[Any]], **options: Any) -> Any:
    async def main() -> Any:
        async with AsyncPlatformClient("127.0.0.1", port, **options) as pltf:
            return await asyncio.wait_for(body(pltf), 20)

    return asyncio.run(main())


def test_typed_replies_and_captured_frames(fake: FakePlatform) -> None:
    log: list[tuple[str, bytes]] = []
    fake.pose = (100, 200, -90000)

    async def body(pltf: AsyncPlatformClient) -> tuple[Status, Position]:
        for method, args, _ in CAPTURED:
            await getattr(pltf, method)(*args)
        return await pltf.get_status(), await pltf.get_position(timeout=1)

    status, position = run_with_client(fake.port, body, wire_log=lambda d, b: log.append((d, b)))
    assert status.operation_state is OperationState.ST_OP_NOT_INITIALIZED and status.pose == (100, 200, -90)
    assert position.angle_deg == pytest.approx(-90)
    sent = [b.hex() for d, b in log if d == "send"]
    assert sent[: len(CAPTURED)] == [h.replace(" ", "") for _, _, h in CAPTURED]


def test_concurrent_requests_get_their_own_replies(fake: FakePlatform) -> None:
    fake.reverse = True  # every second reply overtakes the one before

    async def body(pltf: AsyncPlatformClient) -> list[Any]:
        return list(await asyncio.gather(*[pltf.get_status(), pltf.get_position()] * 3))

    replies = run_with_client(fake.port, body)
    assert [type(r).__name__ for r in replies] == ["Status", "Position"] * 3


def test_bring_up_move_and_waits(fake: FakePlatform) -> None:
    async def body(pltf: AsyncPlatformClient) -> Status:
        assert (await pltf.bring_up(timeout=2)).is_ready
        await pltf.set_mode(AUTOMATIC)
        await pltf.wait_mode(AUTOMATIC, timeout=1)
        await pltf.start()
        await pltf.wait_state(RUNNING, timeout=1)
        await pltf.move_abs(x_mm=-300, y_mm=400, angle_mdeg=180000)
        status = await pltf.wait_target_reached(timeout=2, poll=0.01)
        await pltf.stop()
        await pltf.wait_state(READY, timeout=1)
        return status

    assert run_with_client(fake.port, body).pose == (-300, 400, 180)


def test_rejected_command_and_timeout(fake: FakePlatform) -> None:
    async def body(pltf: AsyncPlatformClient) -> None:
        with pytest.raises(Timeout, match="ST_OP_READY not reached"):
            await pltf.wait_state(READY, timeout=0.1)
        await pltf.init_pltf()  # without CMD_CONNECT_TO_PLTF first
        with pytest.raises(CommandRejected, match=r"CMD_INIT_PLTF.*needs CMD_CONNECT_TO_PLTF first"):
            await pltf.wait_state(READY, timeout=0.2)
        await pltf.move_abs(1, 2, 3)
        with pytest.raises(CommandRejected, match=r"CMD_MOVE_ABS.*ST_OP_NOT_INITIALIZED"):
            await pltf.wait_target_reached(timeout=1)

    run_with_client(fake.port, body)


def test_reply_timeout_then_late_reply_dropped(fake: FakePlatform) -> None:
    async def body(pltf: AsyncPlatformClient) -> int:
        fake.reply_delay = 0.3
        with pytest.raises(Timeout, match=r"no reply to CMD_GET_POSITION within 0.05 s"):
            await pltf.get_position(timeout=0.05)
        fake.pose, fake.reply_delay = (9, 0, 0), 0.0
        position = await pltf.get_position()
        assert not pltf.core.unsolicited
        return position.x_mm

    assert run_with_client(fake.port, body) == 9


def test_cancelled_request_does_not_steal_the_next_reply(fake: FakePlatform) -> None:
    async def body(pltf: AsyncPlatformClient) -> int:
        fake.reply_delay = 0.2
        task = asyncio.ensure_future(pltf.get_position())
        await asyncio.sleep(0.05)
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task
        fake.pose, fake.reply_delay = (5, 0, 0), 0.0
        return (await pltf.get_position()).x_mm

    assert run_with_client(fake.port, body) == 5


def test_context_manager_closes_and_later_calls_fail(fake: FakePlatform) -> None:
    async def main() -> AsyncPlatformClient:
        async with AsyncPlatformClient("127.0.0.1", fake.port) as pltf:
            await pltf.get_status()
        assert pltf.closed
        with pytest.raises(ConnectionClosed, match="closed by the client"):
            await pltf.get_status()
        await pltf.close()  # idempotent
        connected = await AsyncPlatformClient.connect("127.0.0.1", fake.port)
        await connected.close()
        return pltf

    asyncio.run(main())
    deadline = time.monotonic() + 5
    while fake.disconnects < 2:
        assert time.monotonic() < deadline
        time.sleep(0.01)


def test_peer_hang_up_and_bad_bytes(fake: FakePlatform) -> None:
    async def hang_up(pltf: AsyncPlatformClient) -> None:
        fake.hang_up_on = "CMD_GET_STATUS"
        pending = await pltf.send(REQUESTS.CMD_GET_POSITION())
        with pytest.raises(ConnectionClosed, match="platform closed the connection"):
            await pltf.get_status()
        assert pending is not None and pending.done and pltf.closed
        with pytest.raises(ConnectionClosed):
            await pltf.start()

    run_with_client(fake.port, hang_up)
    fake.hang_up_on = None

    async def garbage(pltf: AsyncPlatformClient) -> None:
        fake.garbage = b"\xff\x01\xfe\x02\x00\x00\x00\x02\x12\x00"  # a GET_STATUS reply cut short
        with pytest.raises(ProtocolError, match=r"Truncated|shorter"):
            await pltf.get_status()
        assert pltf.closed

    run_with_client(fake.port, garbage)


def test_connect_refused() -> None:
    async def main() -> None:
        with pytest.raises(ConnectionClosed, match="cannot connect"):
            await AsyncPlatformClient.connect("127.0.0.1", 1, connect_timeout=1)

    asyncio.run(main())


def test_live_async(live: LiveServer) -> None:
    async def body(pltf: AsyncPlatformClient) -> float:
        await pltf.bring_up(timeout=10)
        await pltf.set_mode(MotionMode.MODE_MOTION_AUTOMATIC)
        await pltf.start()
        await pltf.wait_state(RUNNING, timeout=5)
        start = await pltf.get_position()
        await pltf.move_rel(x_mm=0, y_mm=300, angle_mdeg=0)
        await pltf.wait_target_reached(timeout=20)
        end, _ = await asyncio.gather(pltf.get_position(), pltf.get_status())
        return math.hypot(end.x_mm - start.x_mm, end.y_mm - start.y_mm)

    assert run_with_client(live.ports[0], body, timeout=5) == pytest.approx(300, abs=30)


def test_a_retried_goal_after_a_refusal_is_driven_to(fake: FakePlatform) -> None:
    # issue 22, bug 1, through the asyncio client (the same judges, erratum E-CLI-001)
    async def body(pltf: AsyncPlatformClient) -> Status:
        await pltf.bring_up(timeout=1)
        await pltf.set_mode(AUTOMATIC)
        await pltf.start()
        fake.plan = PlannerState.PLANNER_COLLISION_TARGET
        await pltf.move_abs(9000, 9000, 0)
        with pytest.raises(CommandRejected, match="PLANNER_COLLISION_TARGET"):
            await pltf.wait_target_reached(timeout=5, poll=0.01)
        fake.plan = PlannerState.PLANNER_PATH_FOUND
        await pltf.move_abs(3000, 200, 0)
        return await pltf.wait_target_reached(timeout=5, poll=0.01)

    status = run_with_client(fake.port, body)
    assert status.target_reached and status.pose == (3000, 200, 0)
