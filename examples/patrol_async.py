"""examples/patrol.py with the asyncio client: the same patrol, options and output lines.

    python examples/patrol_async.py --target 127.0.0.1:10002 --stations Corridor_01,Kitchen,Corridor_02

While the platform drives to a station, a second task on the same connection watches the battery and prints a
``battery NNNNN mV`` line when the voltage drops below ``--low-battery`` (the asyncio client keeps several requests
in flight on one connection; each gets its own reply).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import math
import sys
import xml.etree.ElementTree as ET
from typing import NamedTuple

from pltf.client import (
    AsyncPlatformClient,
    CommandRejected,
    MotionMode,
    OperationState,
    PlatformError,
    Status,
    Timeout,
)

RUNNING, READY = OperationState.ST_OP_RUNNING, OperationState.ST_OP_READY


class Station(NamedTuple):
    name: str
    x_mm: int
    y_mm: int
    angle_deg: float  # roadmap angles are degrees (toolkit erratum E-XML-007)


def target(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise argparse.ArgumentTypeError(f"expected HOST:PORT, got {text!r}")
    return host.strip("[]"), int(port)


def stations_of(roadmap_xml: bytes) -> dict[str, Station]:
    """The stations of a roadmap document (guide 6.5 Roadmap), by name."""
    out = {}
    for st in ET.fromstring(roadmap_xml).iterfind("stations/station"):
        point = st.find("point")
        if point is None:
            continue
        name = st.get("name") or st.get("id") or ""
        out[name] = Station(
            name, int(float(point.get("x", "0"))), int(float(point.get("y", "0"))), float(st.get("angle", "0"))
        )
    return out


async def running_in_automatic(pltf: AsyncPlatformClient) -> None:
    """Bring the platform up and to state Running in mode Automatic (the mode only changes in Ready)."""
    status = await pltf.bring_up(timeout=30)
    if status.motion_mode != MotionMode.MODE_MOTION_AUTOMATIC:
        if status.operation_state != READY:
            await pltf.stop()
            await pltf.wait_state(READY)
        await pltf.set_mode(MotionMode.MODE_MOTION_AUTOMATIC)
        await pltf.wait_mode(MotionMode.MODE_MOTION_AUTOMATIC)
    if (await pltf.get_status()).operation_state != RUNNING:
        await pltf.start()
        await pltf.wait_state(RUNNING)


async def watch_battery(pltf: AsyncPlatformClient, low_mv: int) -> None:
    """Beside the drive, on the same connection: say so when the battery runs low (once per drop)."""
    low = False
    while True:
        volts = (await pltf.get_status()).io_battery_voltage_mv
        if (volts < low_mv) != low:
            low = not low
            if low:
                print(f"battery {volts} mV", flush=True)
        await asyncio.sleep(1.0)


async def drive_to(pltf: AsyncPlatformClient, station: Station, how: str, timeout: float) -> Status:
    if how == "roadmap":
        await pltf.move_to_station(station.name)
    else:
        await pltf.move_abs(x_mm=station.x_mm, y_mm=station.y_mm, angle_mdeg=round(station.angle_deg * 1000))
    return await pltf.wait_target_reached(timeout=timeout)


async def visit(pltf: AsyncPlatformClient, station: Station, args: argparse.Namespace, tolerance: float) -> bool:
    """Drive to ``station``, retrying; True once the platform stands there."""
    attempts = args.retries + 1
    for attempt in range(1, attempts + 1):
        try:
            if attempt > 1:
                await running_in_automatic(pltf)  # an emergency stop or another client may have stopped it
            status = await drive_to(pltf, station, args.drive, args.timeout)
            off = math.hypot(status.pose.x_mm - station.x_mm, status.pose.y_mm - station.y_mm)
            if off <= tolerance:
                x, y, angle = status.pose
                print(f"reached {station.name} x={x:.0f} y={y:.0f} angle={angle:.1f}", flush=True)
                return True
            why = f"stopped {off:.0f} mm from the station"  # e.g. a MOVE_TO_STATION the platform ignored
        except (CommandRejected, Timeout) as exc:
            why = str(exc)
        print(f"refused {station.name} attempt {attempt}/{attempts}: {why}", flush=True)
        if attempt < attempts:
            await asyncio.sleep(args.retry_delay)
    print(f"skipped {station.name}", flush=True)
    return False


async def patrol(pltf: AsyncPlatformClient, args: argparse.Namespace) -> int:
    known = stations_of((await pltf.get_roadmap()).xml)
    names = args.stations.split(",") if args.stations else list(known)
    missing = [n for n in names if n not in known]
    if missing or not names:
        print(
            f"patrol: error: no station {', '.join(missing)} in the roadmap (it has: {', '.join(known)})",
            file=sys.stderr,
        )
        return 2
    # target reached means within TargetReachedTolPos of the goal (toolkit erratum E-PAR-021); allow it twice
    tolerance = 2.0 * float((await pltf.get_pltf_param("TargetReachedTolPos")).typed_value)
    await running_in_automatic(pltf)
    battery = asyncio.create_task(watch_battery(pltf, args.low_battery))
    try:
        all_reached = True
        rounds = 0
        while args.rounds == 0 or rounds < args.rounds:
            for name in names:
                all_reached &= await visit(pltf, known[name], args, tolerance)
            rounds += 1
            print(f"round {rounds} done", flush=True)
        return 0 if all_reached else 1
    finally:
        battery.cancel()
        with contextlib.suppress(asyncio.CancelledError, PlatformError):
            await battery


async def run(args: argparse.Namespace) -> int:
    host, port = args.target
    async with AsyncPlatformClient(host, port, timeout=10.0) as pltf:
        return await patrol(pltf, args)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--target", type=target, default=("127.0.0.1", 10002), help="HOST:PORT of PlatformCtrl")
    parser.add_argument("--stations", help="comma-separated station names (default: every station of the roadmap)")
    parser.add_argument("--rounds", type=int, default=1, help="rounds to drive (0: until Ctrl-C; default 1)")
    parser.add_argument("--retries", type=int, default=3, help="retries of a refused goal (default 3)")
    parser.add_argument("--retry-delay", type=float, default=2.0, help="seconds before a retry (default 2)")
    parser.add_argument("--timeout", type=float, default=180.0, help="seconds to reach one station (default 180)")
    parser.add_argument(
        "--drive",
        choices=("plan", "roadmap"),
        default="plan",
        help="plan: CMD_MOVE_ABS, the planner's path (default); roadmap: CMD_MOVE_TO_STATION",
    )
    parser.add_argument("--low-battery", type=int, default=22000, help="mV below which to warn (default 22000)")
    args = parser.parse_args(argv)
    try:
        return asyncio.run(run(args))
    except (PlatformError, ET.ParseError) as exc:
        print(f"patrol: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
