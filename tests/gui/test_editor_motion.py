"""The editors (issue 20) end to end in Debian's chromium against the reference server: what the editor sends
changes how the platform drives. The platform is driven and watched over its OTHER port with a plain client."""

from __future__ import annotations

import functools
import itertools
import json
import math
import time
import xml.etree.ElementTree as ET
from typing import Any

from pltf.client import MotionMode, OperationState
from tests.gui.conftest import Gateway, Platform, aim, expect_text, open_gui, wait_for
from tests.gui.test_editor import _objects, _open_editor, _sent

Trace = list[tuple[float, float]]


def drag(page: Any, a: tuple[float, float], b: tuple[float, float]) -> None:
    start, end = aim(page, *a), aim(page, *b)
    page.mouse.move(*start)
    page.mouse.down()
    page.mouse.move(*end, steps=5)
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


STATIONS = [("Alpha", 3000, 10000, 0), ("Bravo", 5000, 9400, 0), ("Charlie", 5000, 12500, 90)]


def selected(state: Any) -> dict[str, object]:
    """The roadmap editor's selected station: name, x, y (mm) and angle (degrees)."""
    s: dict[str, object] = json.loads(state.get_attribute("data-selected") or "{}")
    return {k: s.get(k) for k in ("name", "x", "y", "angle")}


def has_pose(state: Any, want: dict[str, object]) -> bool:
    return selected(state) == want


def attr_is(locator: Any, name: str, value: str) -> bool:
    return bool(locator.get_attribute(name) == value)


def _open_roadmap_editor(page: Any, gateway: Gateway, platform: Platform) -> Any:
    open_gui(page, gateway, platform.target)
    page.get_by_role("menuitem", name="Edit", exact=True).click()
    page.get_by_role("menuitem", name="Edit Roadmap", exact=True).click()
    return page.locator("output.rm-state")


def test_a_three_station_roadmap_built_in_the_editor_is_followed_by_move_to_station(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    state = _open_roadmap_editor(page, gateway, platform)
    page.get_by_role("button", name="New roadmap", exact=True).click()
    page.get_by_role("button", name="Add a station", exact=True).click()
    for k, (name, x, y, angle) in enumerate(STATIONS):
        page.get_by_role("textbox", name="Station name").fill(name)
        page.get_by_role("spinbutton", name="Angle (degrees)").fill(str(angle))
        page.mouse.click(*aim(page, x + 120, y - 90))  # near the pose; the typed coordinates make it exact
        wait_for(functools.partial(attr_is, state, "data-stations", str(k + 1)), what=f"station {name}")
        page.get_by_role("spinbutton", name="X (mm)").fill(str(x))
        page.get_by_role("spinbutton", name="Y (mm)").fill(str(y))
        page.get_by_role("button", name="Apply pose", exact=True).click()
        want: dict[str, object] = {"name": name, "x": x, "y": y, "angle": angle}
        wait_for(functools.partial(has_pose, state, want), what=f"the pose of {name}")
    page.get_by_role("button", name="Add an edge", exact=True).click()
    for a, b in [(0, 1), (1, 2)]:
        page.mouse.click(*aim(page, *STATIONS[a][1:3]))
        page.mouse.click(*aim(page, *STATIONS[b][1:3]))
    wait_for(lambda: state.get_attribute("data-edges") == "2", what="two edges")
    page.get_by_role("button", name="Undo", exact=True).click()
    wait_for(lambda: state.get_attribute("data-edges") == "1", what="undo of the second edge")
    page.get_by_role("button", name="Redo", exact=True).click()
    wait_for(lambda: state.get_attribute("data-edges") == "2", what="redo of the second edge")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    expect_text(page.get_by_role("status", name="Messages", exact=True), "Roadmap sent to the platform")

    # over the other port: the platform's roadmap is the one built, exactly
    def sent() -> Any:
        root = ET.fromstring(platform.other.get_roadmap().xml)
        return len(root.findall("stations/station")) == 3 and root

    root = wait_for(sent, what="the roadmap sent")
    ids = {}
    for st, (name, x, y, angle) in zip(root.findall("stations/station"), STATIONS, strict=True):
        p = st.find("point")
        assert p is not None
        assert (st.get("name"), float(p.get("x", "")), float(p.get("y", "")), float(st.get("angle", ""))) == (
            name,
            x,
            y,
            angle,
        )
        ids[st.get("id")] = name
    assert [(ids[e.get("startstation")], ids[e.get("endstation")]) for e in root.findall("edges/edge")] == [
        ("Alpha", "Bravo"),
        ("Bravo", "Charlie"),
    ]

    running_automatic(platform)
    platform.other.move_to_station("Charlie")
    trace = drive(platform, (5000, 12500))
    # along the roadmap: through Bravo, 600 mm south of the corridor's centre line, which no planned way passes
    near_bravo = min(math.dist(p, (5000, 9400)) for p in trace)
    assert near_bravo <= 150, f"the platform kept {near_bravo:.0f} mm from station Bravo: it did not follow the roadmap"
