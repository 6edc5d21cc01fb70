"""Scenario harness for the world: a platform on a map, stepped in simulated time, its true trajectory kept.

``Sim.run(seconds, until=...)`` advances 50 Hz periods (like the server's control loop) and samples the true
pose every period; ``assert_clear_of`` checks a trajectory against walls (no contact, no crossing, the
footprint's half width of free space around the wheel axis at every sample).
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

from pltf.reference_server.world import MapGeometry, World
from pltf.reference_server.world.geometry import F64, circles, clearance, segments, segments_clear
from pltf.spec.documents import DocumentKind, validate_document
from pltf.spec.parameters import ParameterStore

DT = 0.02
FIXTURES = Path(__file__).resolve().parents[3] / "fixtures"
OFFICE_MAP = FIXTURES / "maps" / "office.map"
OFFICE_ROADMAP = FIXTURES / "roadmaps" / "office.rm"
CORRIDOR_WEST = (1000.0, 10000.0, 0.0)  # station Corridor_W, facing east


@dataclass
class Sim:
    world: World
    params: ParameterStore
    now: float = 0.0
    trace: list[tuple[float, float, float]] = field(default_factory=list)
    contacts: int = 0
    events: list[str] = field(default_factory=list)

    def run(self, seconds: float, until: Callable[[World], bool] | None = None) -> bool:
        """Advance up to ``seconds``; True when ``until`` became true (checked after each period)."""
        for _ in range(round(seconds / DT)):
            self.now = round(self.now + DT, 9)
            self.events += self.world.advance(self.now, DT)
            self.trace.append(self.world.truth)
            self.contacts += self.world.contact
            if until is not None and until(self.world):
                return True
        return until is None

    def until_idle(self, seconds: float = 120.0) -> bool:
        return self.run(seconds, lambda w: not w.active)

    def set(self, name: str, value: object) -> None:
        """CMD_SET_PLTF_PARAM (writable parameters)."""
        self.params.set_text(name, _text(value))


def _text(value: object) -> str:
    return str(value).lower() if isinstance(value, bool) else str(value)


def office_geometry() -> MapGeometry:
    return MapGeometry.from_tree(validate_document(DocumentKind.MAP, OFFICE_MAP.read_bytes()))


def geometry_of(walls: list[tuple[float, float, float, float]], **kw: object) -> MapGeometry:
    return MapGeometry(walls=segments(walls), **kw)  # type: ignore[arg-type]


def room(w: float, h: float) -> list[tuple[float, float, float, float]]:
    return [(0, 0, w, 0), (w, 0, w, h), (w, h, 0, h), (0, h, 0, 0)]


def make_sim(geometry: MapGeometry | None, pose: tuple[float, float, float], seed: int = 1, **params: object) -> Sim:
    store = ParameterStore(startup={name: _text(value) for name, value in params.items()})
    world = World(store.get, random.Random(seed), pose)
    world.set_map(geometry)
    return Sim(world, store)


@pytest.fixture(scope="session")
def office() -> MapGeometry:
    return office_geometry()


def within(world: World, goal: tuple[float, float, float], pos: float, angle_deg: float, truth: bool = True) -> bool:
    x, y, a = world.truth if truth else world.estimate
    err = (a - goal[2] + math.pi) % (2 * math.pi) - math.pi
    return math.hypot(x - goal[0], y - goal[1]) <= pos and abs(math.degrees(err)) <= angle_deg


def assert_clear_of(
    trace: list[tuple[float, float, float]], walls: F64, half_width: float, circs: F64 | None = None
) -> None:
    """The wheel axis' midpoint never crossed a wall and always kept ``half_width`` from every wall."""
    pts = np.asarray(trace)
    c = circles([]) if circs is None else circs
    steps = np.column_stack([pts[:-1, :2], pts[1:, :2]])
    crossed = ~segments_clear(steps, walls, circles([]), 0.0)
    assert not crossed.any(), f"trajectory crosses a wall at {pts[:-1][crossed][:3]}"
    free = clearance(pts[:, 0], pts[:, 1], walls, c)
    assert free.min() >= half_width, f"came within {free.min():.0f} mm of a wall at {pts[free.argmin()]}"
