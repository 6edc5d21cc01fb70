"""The editors (issue 20) end to end in Debian's chromium against the reference server: what the editor sends
changes how the platform drives. The platform is driven and watched over its OTHER port with a plain client."""

from __future__ import annotations

import itertools
import json
import math
import time
from typing import Any

from pltf.client import MotionMode, OperationState
from tests.gui.conftest import Gateway, Platform, expect_text, wait_for
from tests.gui.test_editor import _objects, _open_editor, _sent

Trace = list[tuple[float, float]]


def screen(page: Any, x: float, y: float) -> tuple[float, float]:
    """The page coordinates of the world point (x, y) mm on the map view."""
    canvas = page.get_by_role("img", name="Map")
    cam = json.loads(canvas.get_attribute("data-camera"))
    box = canvas.bounding_box()
    sx = box["x"] + (x - cam["cx"]) * cam["scale"] + cam["width"] / 2
    sy = box["y"] + (cam["cy"] - y) * cam["scale"] + cam["height"] / 2
    return sx, sy


def drag(page: Any, a: tuple[float, float], b: tuple[float, float]) -> None:
    page.mouse.move(*screen(page, *a))
    page.mouse.down()
    page.mouse.move(*screen(page, *b), steps=5)
    page.mouse.up()


def running_automatic(platform: Platform) -> None:
    c = platform.other
    c.connect_to_pltf()
    c.init_pltf()
    wait_for(lambda: c.get_status().operation_state == OperationState.ST_OP_READY, what="Ready")
    c.set_mode(MotionMode.MODE_MOTION_AUTOMATIC)
    c.start()
    wait_for(lambda: c.get_status().operation_state == OperationState.ST_OP_RUNNING, what="Running")


def drive(platform: Platform, goal: tuple[float, float], timeout: float = 60.0) -> Trace:
    """GET_STATUS over the other port until the platform stands at ``goal`` (within 60 mm): its estimated track."""
    trace: Trace = []
    deadline = time.monotonic() + timeout
    while True:
        s = platform.other.get_status()
        trace.append((s.est_x_mm, s.est_y_mm))
        if s.target_reached and math.dist(trace[-1], goal) <= 60 and len(trace) > 1:
            return trace
        assert time.monotonic() < deadline, f"not at {goal} within {timeout} s: last {trace[-1]}"
        time.sleep(0.01)


def crossing_y(trace: Trace, x: float) -> float:
    """Where the track (joined sample to sample) crosses the vertical x."""
    for (x0, y0), (x1, y1) in itertools.pairwise(trace):
        if (x0 - x) * (x1 - x) <= 0 and x0 != x1:
            return y0 + (y1 - y0) * (x - x0) / (x1 - x0)
    raise AssertionError(f"the track never crosses x = {x}")


def test_a_wall_drawn_across_the_corridor_makes_move_abs_plan_around_it(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    # the platform starts at (2000, 10000) facing east in the corridor (y 8800 .. 11200) of fixtures/maps/office.map
    original = platform.other.get_map().xml
    n = len(_objects(original))
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: state.get_attribute("data-objects") == str(n), what="the loaded map")
    page.get_by_role("button", name="Add a line", exact=True).click()
    # a wall from beyond the corridor's south wall to its centre line: the straight way east is closed,
    # the northern half (y 10000 .. 11200) stays open
    drag(page, (4000, 8300), (4000, 10100))
    wait_for(lambda: state.get_attribute("data-objects") == str(n + 1), what="the drawn wall")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    expect_text(page.get_by_role("status", name="Messages", exact=True), "Map sent to the platform")
    walls = [o for o in _objects(_sent(platform, original)) if o[0] == "line"]
    (_, _, pts) = walls[-1]
    (x0, y0), (x1, y1) = ((float(p["x"]), float(p["y"])) for _, p in pts)
    assert abs(x0 - 4000) <= 60 and abs(x1 - 4000) <= 60 and y0 <= 8800 and y1 >= 10000, pts

    running_automatic(platform)
    platform.other.move_abs(6000, 10000, 0)  # straight ahead, 4 m east, behind the wall
    trace = drive(platform, (6000, 10000))
    y = crossing_y(trace, (x0 + x1) / 2)
    assert y >= max(y0, y1) + 250, f"the platform passed the wall's line at y {y:.0f}: through or at the wall"
    assert y <= 11200 - 250, f"the platform passed at y {y:.0f}: through the corridor's north wall"
