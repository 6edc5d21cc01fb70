"""examples/dispatcher.py against a fleet (``pltf serve --fleet FILE``): every platform ends on a station of its
own, and a platform that is refused its station is sent to another one.

The fleet file puts a platform 1 m inside a room beyond the room's station (two rooms, or all eight) and one at
each end of the corridor, so each one's nearest station is a different one. The
fleet runs without the fake CAN boards (``--no-hardware``) at time scale 2: the dispatcher judges only what the
socket API reports. The refusal is real: before the dispatcher starts, the test gives the platform at the
corridor's west end (and only it) a map with a pillar on station Corridor_W, so its planner answers
PLANNER_COLLISION_TARGET; the dispatcher must then send it to the spare station Corridor_01 and leave Corridor_W
free. (A pillar on a room's station would also close the room's door, 1 m away, to its platform.) The test checks
the end through its own connections on the platforms' other ports (GET_POSITION).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import pytest

from pltf.client import PlatformClient
from tests.examples.runner import Example, python_example
from tests.reference_server.test_fleet_conformance import FleetProcess

ROOMS = {  # station: (x, y) of the station; the platform starts 1 m further into the room
    "Kitchen": (5000, 12200),
    "Meeting": (8500, 12200),
    "Office_N1": (19000, 12200),
    "Office_N2": (24800, 12200),
    "Lab": (7000, 7800),
    "Server": (10600, 7800),
    "Office_S1": (21000, 7800),
    "Storage": (27500, 7800),
}
ENDS = {"Corridor_W": ((1000, 10000), (2500, 10000)), "Charging": ((31200, 10000), (29500, 10000))}
SPARE = "Corridor_01"  # (5000, 10000): the nearest station left for the west end's platform once Corridor_W is refused
STATIONS = {**ROOMS, **{k: v[0] for k, v in ENDS.items()}, SPARE: (5000, 10000)}  # the jobs, for every fleet
PILLAR = '<circle><center x="1000" y="10000"/><radius r="300"/></circle>'  # on station Corridor_W
TOLERANCE = 2 * 100  # twice TargetReachedTolPos (100 mm)


def starts(rooms: int) -> list[dict[str, object]]:
    """The fleet file's platforms: the first ``rooms`` rooms' and the corridor's two ends'."""
    out: list[dict[str, object]] = []
    for name, (x, y) in list(ROOMS.items())[:rooms]:
        inward = 1000 if y > 10000 else -1000
        out.append({"name": name.lower(), "ports": [0, 0], "pose": {"x": x, "y": y + inward, "angle": 0}})
    for name, (_, (x, y)) in ENDS.items():
        out.append({"name": name.lower(), "ports": [0, 0], "pose": {"x": x, "y": y, "angle": 0}})
    return out


# both behind slow: a fleet process and a dispatcher run cost 25-45 s of the default tier's budget at load 20-30
# (the 4-platform one: 28 s at load 20), more than this whole share of it
@pytest.fixture(
    params=[
        pytest.param(2, id="4 platforms", marks=pytest.mark.slow),
        pytest.param(8, id="10 platforms", marks=pytest.mark.slow),
    ]
)
def fleet(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[FleetProcess]:
    platforms = starts(request.param)
    srv = FleetProcess(tmp_path, len(platforms), platforms, "--no-hardware", time_scale=2.0)
    try:
        yield srv
    finally:
        srv.stop()


def test_each_platform_on_a_station_of_its_own_and_the_blocked_one_sent_elsewhere(fleet: FleetProcess) -> None:
    order = [str(name) for name in fleet.ports]
    watch = {name: PlatformClient("127.0.0.1", fleet.ports[str(name)][1], timeout=10) for name in order}
    try:
        west = watch["corridor_w"]
        office = west.get_map()
        west.set_map(office.name, office.xml.decode().replace('<layer index="1">', f'<layer index="1">{PILLAR}', 1))
        targets = [a for name in order for a in ("--target", f"127.0.0.1:{fleet.ports[str(name)][0]}")]
        cmd = python_example("dispatcher.py", *targets, "--stations", ",".join(STATIONS), "--timeout", "60")
        with Example(cmd) as run:
            assert run.finish(timeout=240) == 0, "\n".join([*run.lines, run.stderr()])
        names = {f"p{k + 1}": name for k, name in enumerate(order)}  # the dispatcher's names, in --target order
        blocked = [line for line in run.lines if line.startswith("blocked")]
        short = {name: f"p{k + 1}" for k, name in enumerate(order)}["corridor_w"]  # the dispatcher's name for it
        assert len(blocked) == 1 and blocked[0].startswith(f"blocked {short} Corridor_W:"), run.lines
        assert "PLANNER_COLLISION_TARGET" in blocked[0], blocked
        reached = {line.split()[1]: line.split()[2] for line in run.lines if line.startswith("reached")}
        assert reached[short] == SPARE, run.lines
        assert len(set(reached.values())) == len(reached) == len(order), reached  # never two on one station
        assert "Corridor_W" not in reached.values()
        assert run.lines[-1] == f"done {len(order)}/{len(order)}"
        for short, station in reached.items():  # where each platform really stands, asked on its other port
            pos = watch[str(names[short])].get_position()
            sx, sy = STATIONS[station]
            assert math.hypot(pos.x_mm - sx, pos.y_mm - sy) <= TOLERANCE, (short, station, pos)
    finally:
        for c in watch.values():
            c.close()
