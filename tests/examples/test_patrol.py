"""examples/patrol.py and its twins (patrol_async.py, typescript/patrol.ts, cpp/patrol.cpp) against the reference
server: the stations are visited in order, and a goal the platform refuses is retried and reached.

The refusal is real: the test puts a pillar on station Kitchen (a map with one more circle, sent with
CMD_SET_MAP from a second connection), so the planner answers PLANNER_COLLISION_TARGET; when the patrol reports
the refusal, the test takes the pillar away again and the patrol's retry must reach Kitchen. Before erratum
E-CLI-001 every retry was judged by the refusal before it (issue 22) and Kitchen was skipped.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator

import pytest

from pltf.client import Map, PlatformClient
from tests.clients.client_fakes import LiveServer
from tests.examples.builds import build
from tests.examples.runner import Example, python_example, target

STATIONS = {"Corridor_01": (5000, 10000, 0.0), "Kitchen": (5000, 12200, 90.0), "Corridor_02": (7000, 10000, 0.0)}
ROUTE = ",".join(STATIONS)
PILLAR = '<circle><center x="5000" y="12200"/><radius r="300"/></circle>'  # on station Kitchen
REACHED = re.compile(r"reached (\S+) x=(-?\d+) y=(-?\d+) angle=(-?[\d.]+)$")


@pytest.fixture(scope="module")
def watch(server: LiveServer) -> Iterator[PlatformClient]:
    """The test's own connection, on the server's second port."""
    with PlatformClient("127.0.0.1", server.ports[1], timeout=10) as client:
        yield client


def blocked(office: Map) -> bytes:
    xml = office.xml.decode("utf-8")
    return xml.replace('<layer index="1">', f'<layer index="1">\n    {PILLAR}', 1).encode("utf-8")


def command(kind: str) -> list[str]:
    if kind in ("typescript", "cpp"):
        return build(kind).command("patrol")  # built once, cached by content (tests/examples/builds.py)
    return python_example({"sync": "patrol.py", "async": "patrol_async.py"}[kind])


@pytest.mark.parametrize("kind", ["sync", "async", "typescript", "cpp"])
def test_patrol_visits_the_stations_in_order_and_retries_a_refused_goal(
    kind: str, server: LiveServer, watch: PlatformClient
) -> None:
    cmd = command(kind)
    office = watch.get_map()
    watch.set_map(office.name, blocked(office))
    run = Example([*cmd, "--target", target(server), "--stations", ROUTE, "--retries", "3", "--retry-delay", "1"])
    try:
        run.expect("reached Corridor_01")
        refused = run.expect("refused Kitchen attempt 1/4")
        assert "PLANNER_COLLISION_TARGET" in refused, refused
        watch.set_map(office.name, office.xml)  # the pillar goes; the retry must be judged by its own outcome
        assert run.finish(timeout=60) == 0, (run.lines, run.stderr())
    finally:
        run.close()
        watch.set_map(office.name, office.xml)
    visits = [m.groups() for line in run.lines if (m := REACHED.match(line))]
    assert [v[0] for v in visits] == list(STATIONS), run.lines
    for name, x, y, angle in visits:
        sx, sy, sa = STATIONS[name]
        assert math.hypot(int(x) - sx, int(y) - sy) <= 40, (name, x, y)
        assert abs((float(angle) - sa + 180) % 360 - 180) <= 3, (name, angle)
    assert [line for line in run.lines if line.startswith("refused")] == [refused]  # one refusal, one retry
    assert run.lines[-1] == "round 1 done"


def test_an_unknown_station_is_a_usage_error(server: LiveServer) -> None:
    with Example(python_example("patrol.py", "--target", target(server), "--stations", "Corridor_01,Attic")) as run:
        assert run.finish() == 2
    assert "no station Attic in the roadmap" in run.stderr()


def test_patrol_along_the_roadmap(server: LiveServer) -> None:
    cmd = python_example(
        "patrol.py", "--target", target(server), "--stations", "Corridor_02,Corridor_01", "--drive", "roadmap"
    )
    with Example(cmd) as run:
        assert run.finish(timeout=60) == 0, (run.lines, run.stderr())
    assert [m.group(1) for line in run.lines if (m := REACHED.match(line))] == ["Corridor_02", "Corridor_01"]
