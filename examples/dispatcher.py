"""Dispatch a fleet to stations: every platform to a station of its own, never two to one, recovering when one is
blocked.

    python examples/dispatcher.py --target 127.0.0.1:10002 --target 127.0.0.1:10006 ... --stations Kitchen,Lab,...

Each ``--target`` is one platform (its application port; ``pltf serve --fleet`` prints them), named p1, p2, ... in
the order given. The stations (``--stations``, default every station) come from the roadmap of the first platform
(CMD_GET_ROADMAP). The dispatcher:

- first assigns stations to all platforms at once, nearest pairs first (the platform and the free station with the
  least straight-line distance, then the next pair of the rest, ...), so no two platforms head for one station;
- drives every platform at the same time (a thread and a connection each) with CMD_MOVE_ABS, the planner's path,
  and waits for its target reached;
- when a platform is blocked - the platform refuses the goal (the planner's state: a collision at the target, no
  path) or does not reach it within ``--timeout`` seconds - the station goes back to the pool for the others and
  the platform gets the nearest free station it was not refused at; a station is never given to two platforms:
  it stays taken while a platform drives to it or stands on it;
- a platform for which no station is left waits until one is released or every other platform has finished.

One line per event on standard output: ``assigned NAME STATION``, ``reached NAME STATION x=.. y=..``, ``blocked
NAME STATION: why``, ``idle NAME: no free station``, ``done PLACED/PLATFORMS``. Exit status 0 when every platform
stands on a station of its own, 1 when one does not, 2 when a platform cannot be used (unreachable, bad arguments,
no such station).
"""

from __future__ import annotations

import argparse
import math
import sys
import threading
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

from patrol import Station, running_in_automatic, stations_of, target  # the patrol's platform helpers

from pltf.client import CommandRejected, PlatformClient, PlatformError, Timeout


def say(line: str) -> None:
    print(line, flush=True)


@dataclass
class Board:
    """Who has which station: the one place the dispatcher decides, under one lock."""

    stations: dict[str, Station]
    taken: dict[str, str] = field(default_factory=dict)  # station -> platform driving to it or standing on it
    refused: set[tuple[str, str]] = field(default_factory=set)  # (platform, station) pairs that did not work
    driving: int = 0  # platforms with a station to reach
    lock: threading.Condition = field(default_factory=threading.Condition)

    def assign_all(self, poses: dict[str, tuple[float, float]]) -> dict[str, Station]:
        """The first assignment: nearest (platform, free station) pairs first."""
        pairs = sorted(
            (math.hypot(st.x_mm - x, st.y_mm - y), name, st.name)
            for name, (x, y) in poses.items()
            for st in self.stations.values()
        )
        out: dict[str, Station] = {}
        with self.lock:
            for _, name, station in pairs:
                if name not in out and station not in self.taken:
                    self.taken[station] = name
                    out[name] = self.stations[station]
            self.driving = len(out)
        return out

    def _nearest_free(self, name: str, x: float, y: float) -> Station | None:
        free = [
            st for st in self.stations.values() if st.name not in self.taken and (name, st.name) not in self.refused
        ]
        return min(free, key=lambda st: math.hypot(st.x_mm - x, st.y_mm - y), default=None)

    def release(self, name: str, station: Station) -> None:
        """``name`` could not reach ``station``: it is free again, but not for ``name``."""
        with self.lock:
            self.refused.add((name, station.name))
            del self.taken[station.name]
            self.driving -= 1
            self.lock.notify_all()

    def reached(self) -> None:
        with self.lock:
            self.driving -= 1
            self.lock.notify_all()

    def claim(self, name: str, x: float, y: float) -> Station | None:
        """The nearest free station ``name`` was not refused at; waits while others drive; None: none is left."""
        with self.lock:
            while True:
                st = self._nearest_free(name, x, y)
                if st is not None:
                    self.taken[st.name] = name
                    self.driving += 1
                    return st
                if self.driving == 0:  # nobody can release one any more
                    return None
                self.lock.wait()


def drive(pltf: PlatformClient, st: Station, timeout: float) -> tuple[bool, str, tuple[float, float]]:
    """(reached, why not, the pose it stands at)."""
    try:
        running_in_automatic(pltf)  # an emergency stop or another client may have stopped it
        pltf.move_abs(x_mm=st.x_mm, y_mm=st.y_mm, angle_mdeg=round(st.angle_deg * 1000))
        status = pltf.wait_target_reached(timeout=timeout)
    except (CommandRejected, Timeout) as exc:
        pltf.stop()  # a platform that timed out must not drive on into a station given to another
        pose = pltf.get_position()
        return False, str(exc), (pose.x_mm, pose.y_mm)
    return True, "", (status.pose.x_mm, status.pose.y_mm)


def run_platform(
    name: str, pltf: PlatformClient, board: Board, first: Station | None, args: argparse.Namespace
) -> Station | None:
    """Drive ``name`` until it stands on a station of its own (returned) or none is left (None)."""
    station = first
    pose = pltf.get_position()
    x, y = float(pose.x_mm), float(pose.y_mm)
    while True:
        if station is None:
            station = board.claim(name, x, y)
            if station is None:
                say(f"idle {name}: no free station")
                return None
        say(f"assigned {name} {station.name}")
        ok, why, (x, y) = drive(pltf, station, args.timeout)
        if ok:
            board.reached()
            say(f"reached {name} {station.name} x={x:.0f} y={y:.0f}")
            return station
        say(f"blocked {name} {station.name}: {why}")
        board.release(name, station)
        station = None


def dispatch(clients: dict[str, PlatformClient], args: argparse.Namespace) -> int:
    first = next(iter(clients.values()))
    known = stations_of(first.get_roadmap().xml)
    names = args.stations.split(",") if args.stations else list(known)
    missing = [n for n in names if n not in known]
    if missing or not names:
        print(f"dispatcher: error: no station {', '.join(missing)} in the roadmap", file=sys.stderr)
        return 2
    board = Board({n: known[n] for n in names})
    poses = {name: (float(p.x_mm), float(p.y_mm)) for name, c in clients.items() for p in [c.get_position()]}
    for c in clients.values():
        running_in_automatic(c)
    plan = board.assign_all(poses)
    results: dict[str, Station | None] = {}

    def work(name: str) -> None:
        results[name] = run_platform(name, clients[name], board, plan.get(name), args)

    threads = [threading.Thread(target=work, args=(name,), name=name) for name in clients]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    placed = [st.name for st in results.values() if st is not None]
    say(f"done {len(placed)}/{len(clients)}")
    return 0 if len(placed) == len(clients) else 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--target", type=target, action="append", required=True, help="HOST:PORT of one platform (repeat)"
    )
    parser.add_argument("--stations", help="comma-separated station names (default: every station of the roadmap)")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds to reach one station (default 120)")
    args = parser.parse_args(argv)
    clients: dict[str, PlatformClient] = {}
    try:
        for k, (host, port) in enumerate(args.target):
            clients[f"p{k + 1}"] = PlatformClient(host, port, timeout=10.0)
        return dispatch(clients, args)
    except (PlatformError, ET.ParseError) as exc:
        print(f"dispatcher: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    finally:
        for c in clients.values():
            c.close()


if __name__ == "__main__":
    sys.exit(main())
