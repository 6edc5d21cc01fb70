"""Map loading (guide 6.5) and the vectorised distance functions, against brute force."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from pltf.reference_server.world import geometry
from pltf.reference_server.world.geometry import (
    MapGeometry,
    circles,
    clearance,
    inside_polygon,
    point_segment_distance,
    segments,
    segments_clear,
    segments_clear_numpy,
)
from pltf.spec.documents import DocumentKind, validate_document

MAP = b"""<?xml version="1.0"?>
<map Version="1.0"><layer index="0">
  <workarea><point x="0" y="0"/><point x="10000" y="8000"/></workarea>
  <line><point x="0" y="0"/><point x="10000" y="0"/></line>
  <linemapped><point x="10000" y="0"/><point x="10000" y="8000"/></linemapped>
  <auxline><point x="2000" y="2000"/><point x="3000" y="2000"/></auxline>
  <auxlinemapped><point x="5000" y="5000"/><point x="5000" y="6000"/></auxlinemapped>
  <circle><center x="7000" y="3000"/><radius r="300"/></circle>
  <reflmark><point x="4950" y="0"/><point x="5050" y="0"/></reflmark>
  <reflmark><point x="10000" y="4000"/></reflmark>
  <prohibit><point x="6000" y="6000"/><point x="8000" y="6000"/><point x="8000" y="7500"/></prohibit>
  <hiddenlabel text="ignored"><point x="1" y="1"/></hiddenlabel>
</layer></map>"""


def test_every_element_of_a_map_is_read() -> None:
    g = MapGeometry.from_tree(validate_document(DocumentKind.MAP, MAP))
    assert g.walls.tolist() == [[0, 0, 10000, 0], [10000, 0, 10000, 8000]]
    assert g.aux.tolist() == [[2000, 2000, 3000, 2000], [5000, 5000, 5000, 6000]]
    assert g.circles.tolist() == [[7000, 3000, 300]]
    assert g.reflectors.tolist() == [[4950, 0, 5050, 0], [10000, 4000, 10000, 4000]]  # a point reflector
    assert len(g.obstacles) == 4
    # a two-point area is the rectangle it spans (E-MOT-001); the triangle is kept as given
    assert g.workareas[0].tolist() == [[0, 0], [10000, 0], [10000, 8000], [0, 8000]]
    assert len(g.prohibited[0]) == 3
    assert len(g.constraint_edges()) == 4 + 3
    assert g.corners().tolist() == [[10000.0, 0.0, 0.0, 0.0]]


def test_allowed_means_inside_the_workarea_and_outside_prohibited_areas() -> None:
    g = MapGeometry.from_tree(validate_document(DocumentKind.MAP, MAP))
    xs = np.array([5000.0, -10.0, 7900.0, 6500.0])
    ys = np.array([4000.0, 4000.0, 6100.0, 7000.0])
    assert g.allowed(xs, ys).tolist() == [True, False, False, True]
    assert MapGeometry().allowed(xs, ys).all()  # no workarea: everywhere


def test_office_map(office: MapGeometry) -> None:
    assert len(office.walls) == 20 and len(office.aux) == 3 and len(office.circles) == 6
    assert len(office.reflectors) == 6 and len(office.prohibited) == 1
    corners = {(c[0], c[1]) for c in office.corners().tolist()}
    assert {(0.0, 0.0), (32000.0, 20000.0), (7000.0, 11200.0), (9000.0, 8800.0)} <= corners
    assert (5000.0, 11200.0) not in corners  # the middle of a door opening
    assert (4400.0, 11200.0) not in corners  # a door jamb: a wall's free end
    t = office.corners()[(office.corners()[:, 0] == 7000.0) & (office.corners()[:, 1] == 11200.0)]
    assert t[0, 2:].tolist() == pytest.approx([0.0, 1.0])  # a T shows to the room it divides, not the corridor


def _brute_segment_distance(q: list[float], s: list[float]) -> float:
    ts = np.linspace(0, 1, 401)
    a = np.array(q[:2])[None, :] + ts[:, None] * (np.array(q[2:]) - np.array(q[:2]))
    d = point_segment_distance(a[:, 0], a[:, 1], segments(np.array([s])))
    return float(d.min())


def test_segments_clear_against_sampling() -> None:
    rng = random.Random(3)
    for _ in range(200):
        q = [rng.uniform(0, 1000) for _ in range(4)]
        s = [rng.uniform(0, 1000) for _ in range(4)]
        r = rng.uniform(0, 200)
        brute = _brute_segment_distance(q, s)
        if abs(brute - r) < 3.0:
            continue  # the sampling is only good to about a millimetre
        assert bool(segments_clear(np.array([q]), segments(np.array([s])), circles([]), r)[0]) == (brute >= r)


def test_segments_clear_with_circles_and_per_query_radius() -> None:
    q = np.array([[0, 0, 1000, 0], [0, 500, 1000, 500]], dtype=float)
    c = circles([(500, 250, 100)])
    assert segments_clear(q, segments([]), c, 140.0).tolist() == [True, True]
    assert segments_clear(q, segments([]), c, np.array([160.0, 140.0])).tolist() == [False, True]


def test_clearance_and_polygons() -> None:
    walls = segments([(0, 0, 1000, 0)])
    found = clearance(np.array([500.0, 1500.0]), np.array([300.0, 0.0]), walls, circles([(500, 300, 100)]))
    assert found.tolist() == [-100.0, 500.0]  # negative inside a circle
    square = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], dtype=float)
    assert inside_polygon(np.array([5.0, 15.0]), np.array([5.0, 5.0]), square).tolist() == [True, False]
    assert math.isinf(clearance(np.array([0.0]), np.array([0.0]), segments([]), circles([]))[0])


def test_segments_clear_runs_in_c() -> None:
    assert geometry.HAVE_C


@pytest.mark.parametrize("seed", range(6))
def test_segments_clear_in_c_equals_numpy(seed: int) -> None:
    """The C loops answer as numpy does, query by query: crossings, near misses, degenerate queries and walls,
    circles a (negative) radius shrinks away, one radius or one per query."""
    rng = np.random.default_rng(seed)
    for k in range(40):
        nq, ns, nc = (int(rng.integers(0, n)) for n in (150, 50, 6))
        q = rng.uniform(0, 10000, (nq, 4))
        q[: nq // 4, 2:] = q[: nq // 4, :2]  # points
        walls = rng.uniform(0, 10000, (ns, 4))
        walls[: ns // 5, 2:] = walls[: ns // 5, :2]
        circs = np.column_stack([rng.uniform(0, 10000, (nc, 2)), rng.uniform(-300, 600, nc)])
        radius = rng.uniform(0, 900) if k % 2 else rng.uniform(-200, 900, nq)
        np.testing.assert_array_equal(
            segments_clear(q, walls, circs, radius), segments_clear_numpy(q, walls, circs, radius)
        )


def test_segments_clear_in_c_refuses_a_short_radius_buffer() -> None:
    from pltf.reference_server.world import _geometry

    q = np.zeros((4, 4))
    with pytest.raises(ValueError, match="one item per query"):
        _geometry.segments_clear(q, np.zeros((1, 4)), np.zeros((0, 3)), np.zeros(2), np.ones(4, dtype=bool))
