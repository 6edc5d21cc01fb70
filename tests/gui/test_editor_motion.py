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


def crossing_x(trace: Trace, y: float) -> float:
    """Where the track (joined sample to sample) crosses the horizontal y."""
    for (x0, y0), (x1, y1) in itertools.pairwise(trace):
        if (y0 - y) * (y1 - y) <= 0 and y0 != y1:
            return x0 + (x1 - x0) * (y - y0) / (y1 - y0)
    raise AssertionError(f"the track never crosses y = {y}")


def test_a_wall_drawn_across_a_room_makes_move_abs_plan_around_it(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    # fixtures/maps/office.map: the platform starts at (2000, 10000) in the corridor; the lab (x 0 .. 9000,
    # y 0 .. 8800) has its door at x 6400 .. 7600. Without the wall, MOVE_ABS to (7000, 3000) drives straight
    # south from the door along x 7000.
    original = platform.other.get_map().xml
    n = len(_objects(original))
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: state.get_attribute("data-objects") == str(n), what="the loaded map")
    page.get_by_role("button", name="Add a line", exact=True).click()
    drag(page, (9000, 6000), (5000, 6000))  # from the lab's east wall to its middle, across the way south
    wait_for(lambda: state.get_attribute("data-objects") == str(n + 1), what="the drawn wall")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    expect_text(page.get_by_role("status", name="Messages", exact=True), "Map sent to the platform")
    walls = [o for o in _objects(_sent(platform, original)) if o[0] == "line"]
    (_, _, pts) = walls[-1]
    (x0, y0), (x1, y1) = ((float(p["x"]), float(p["y"])) for _, p in pts)
    assert abs(y0 - 6000) <= 60 and abs(y1 - 6000) <= 60 and x0 >= 8900 and abs(x1 - 5000) <= 60, pts

    running_automatic(platform)
    platform.other.move_abs(7000, 3000, -90000)
    trace = drive(platform, (7000, 3000))
    x = crossing_x(trace, (y0 + y1) / 2)
    assert x <= min(x0, x1) - 250, f"the platform passed the wall's line at x {x:.0f}: through the wall"
