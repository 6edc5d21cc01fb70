"""Patrol the stations of the platform's roadmap, in order, retrying a goal the platform refuses.

    python examples/patrol.py --target 127.0.0.1:10002 --stations Corridor_01,Kitchen,Corridor_02 --rounds 2

The stations (name, position, angle) come from the roadmap active on the platform (CMD_GET_ROADMAP). Each is
driven to with CMD_MOVE_ABS, the planner's shortest path around walls and obstacles (``--drive roadmap``: with
CMD_MOVE_TO_STATION along the roadmap's edges). A goal the platform refuses (a planner failure, the platform
stopped or in another mode) or does not reach in time is tried again after ``--retry-delay`` seconds, up to
``--retries`` times, bringing the platform back to Running first; then the station is skipped.

One line per event on standard output: ``reached NAME x=.. y=.. angle=..``, ``refused NAME attempt I/N: why``,
``skipped NAME``, ``round R done``. Exit status 0 when every station was reached, 1 when one was skipped, 2 when
the platform cannot be used (unreachable, bad arguments, no such station).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import xml.etree.ElementTree as ET
from typing import NamedTuple

from pltf.client import (
    CommandRejected,
    MotionMode,
    OperationState,
    PlatformClient,
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


def running_in_automatic(pltf: PlatformClient) -> None:
    """Bring the platform up and to state Running in mode Automatic (the mode only changes in Ready)."""
    status = pltf.bring_up(timeout=30)
    if status.motion_mode != MotionMode.MODE_MOTION_AUTOMATIC:
        if status.operation_state != READY:
            pltf.stop()
            pltf.wait_state(READY)
        pltf.set_mode(MotionMode.MODE_MOTION_AUTOMATIC)
        pltf.wait_mode(MotionMode.MODE_MOTION_AUTOMATIC)
    if pltf.get_status().operation_state != RUNNING:
        pltf.start()
        pltf.wait_state(RUNNING)


def drive_to(pltf: PlatformClient, station: Station, how: str, timeout: float) -> Status:
    if how == "roadmap":
        pltf.move_to_station(station.name)
    else:
        pltf.move_abs(x_mm=station.x_mm, y_mm=station.y_mm, angle_mdeg=round(station.angle_deg * 1000))
    return pltf.wait_target_reached(timeout=timeout)


def visit(pltf: PlatformClient, station: Station, args: argparse.Namespace, tolerance: float) -> bool:
    """Drive to ``station``, retrying; True once the platform stands there."""
    attempts = args.retries + 1
    for attempt in range(1, attempts + 1):
        try:
            if attempt > 1:
                running_in_automatic(pltf)  # an emergency stop or another client may have stopped it
            status = drive_to(pltf, station, args.drive, args.timeout)
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
            time.sleep(args.retry_delay)
    print(f"skipped {station.name}", flush=True)
    return False


def patrol(pltf: PlatformClient, args: argparse.Namespace) -> int:
    known = stations_of(pltf.get_roadmap().xml)
    names = args.stations.split(",") if args.stations else list(known)
    missing = [n for n in names if n not in known]
    if missing or not names:
        print(
            f"patrol: error: no station {', '.join(missing)} in the roadmap (it has: {', '.join(known)})",
            file=sys.stderr,
        )
        return 2
    # target reached means within TargetReachedTolPos of the goal (toolkit erratum E-PAR-021); allow it twice
    tolerance = 2.0 * float(pltf.get_pltf_param("TargetReachedTolPos").typed_value)
    running_in_automatic(pltf)
    all_reached = True
    rounds = 0
    while args.rounds == 0 or rounds < args.rounds:
        for name in names:
            all_reached &= visit(pltf, known[name], args, tolerance)
        rounds += 1
        print(f"round {rounds} done", flush=True)
    return 0 if all_reached else 1


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
    args = parser.parse_args(argv)
    host, port = args.target
    try:
        with PlatformClient(host, port, timeout=10.0) as pltf:
            return patrol(pltf, args)
    except (PlatformError, ET.ParseError) as exc:
        print(f"patrol: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
