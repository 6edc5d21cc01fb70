"""The map view's optional layers in Debian's chromium against the reference server (issue 19, 5.3 / 5.7): the
obstacles used for planning while ViewPlanObstEnabled is set (erratum E-GUI-005), and the ground truth read from
the reference server's control channel. What the GUI did to the platform
is checked over the server's OTHER port; what it drew is read from the canvas (counts and pixels).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from pltf.client import PlatformClient
from tests.gui.conftest import Gateway, Platform, expect_text, open_gui, page_point, wait_for
from tests.gui.fakes import free_port
from tests.gui.test_app import init_and_start


def red_near(page: Any, x: float, y: float, radius: int = 3) -> bool:
    """Is a planning-obstacle red pixel within `radius` px of the screen point (page coordinates)?"""
    return bool(
        page.evaluate(
            """([x, y, r]) => {
              const c = document.querySelector('canvas.map-canvas');
              const box = c.getBoundingClientRect();
              const dpr = window.devicePixelRatio || 1;
              const px = Math.round((x - box.left) * dpr), py = Math.round((y - box.top) * dpr);
              const d = c.getContext('2d').getImageData(px - r, py - r, 2 * r + 1, 2 * r + 1).data;
              for (let i = 0; i < d.length; i += 4) {
                const [r_, g, b] = [d[i], d[i + 1], d[i + 2]];
                if (r_ > 150 && g < 30 && b < 30) return true;  // #d50000; the scan is #e53935
              }
              return false;
            }""",
            [x, y, radius],
        )
    )


def observed_midpoints(client: PlatformClient) -> list[tuple[float, float]]:
    """The world-frame midpoints of the lines GET_STATUS reports as observed (platform frame, erratum E-MOT-003)."""
    s = client.get_status()
    a = math.radians(s.est_angle_mdeg / 1000)
    out = []
    for ln in s.lines:
        mx, my = (ln.source_x_mm + ln.target_x_mm) / 2, (ln.source_y_mm + ln.target_y_mm) / 2
        out.append((s.est_x_mm + mx * math.cos(a) - my * math.sin(a), s.est_y_mm + mx * math.sin(a) + my * math.cos(a)))
    return out


def test_planning_obstacles_are_drawn_while_view_plan_obst_enabled_is_set(
    page: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    open_gui(page, gateway, platform.target)
    page.get_by_role("button", name="Zoom all", exact=True).click()
    canvas = page.get_by_role("img", name="Map")
    other = platform.other
    status = other.get_status()
    assert len(status.lines) > 0
    wait_for(lambda: canvas.get_attribute("data-drawn-planobst") == "0", what="no planning obstacles while off")
    page.get_by_role("menuitem", name="View", exact=True).click()
    page.get_by_role("menuitem", name="View Options", exact=True).click()
    switch = page.get_by_role("checkbox", name="Obstacles used for planning (ViewPlanObstEnabled)")
    assert not switch.is_checked()
    switch.check()
    wait_for(lambda: other.get_pltf_param("ViewPlanObstEnabled").value == "true", what="the parameter set")

    def drawn_matches() -> bool:
        s = other.get_status()
        return canvas.get_attribute("data-drawn-planobst") == str(len(s.lines) + len(s.circles))

    wait_for(drawn_matches, what="one drawn obstacle per observed line and circle")
    inside = [
        page_point(page, x, y)
        for x, y in observed_midpoints(other)
        if canvas.bounding_box()["x"]
        < page_point(page, x, y)[0]
        < canvas.bounding_box()["x"] + canvas.bounding_box()["width"]
        and canvas.bounding_box()["y"]
        < page_point(page, x, y)[1]
        < canvas.bounding_box()["y"] + canvas.bounding_box()["height"]
    ]
    assert inside, "no observed line lies in the view"
    wait_for(lambda: all(red_near(page, *p) for p in inside), what=f"red at the observed lines' midpoints {inside}")
    page.screenshot(path=str(artifacts / "planning-obstacles.png"))
    # switched off from the GUI: the platform's parameter and the drawing follow
    switch.uncheck()
    wait_for(lambda: other.get_pltf_param("ViewPlanObstEnabled").value == "false", what="the parameter cleared")
    wait_for(lambda: canvas.get_attribute("data-drawn-planobst") == "0", what="no planning obstacles drawn")
    assert not any(red_near(page, *p) for p in inside)


def test_the_ground_truth_layer_shows_the_true_pose_and_the_injected_faults(
    page: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    """The optional layer (gui/truth.py): ?control=HOST:PORT reads the reference server's control channel."""
    control = f"127.0.0.1:{platform.control.sock.getpeername()[1]}"
    page.goto(f"{gateway.url(platform.target)}&control={control}")
    truth = page.get_by_role("status", name="Ground truth", exact=True)
    true_pose = platform.control("pose")["true"]
    expect_text(truth, f"true pose x {round(true_pose[0])} mm, y {round(true_pose[1])} mm")
    expect_text(truth, "no injected fault")
    canvas = page.get_by_role("img", name="Map")
    wait_for(lambda: canvas.get_attribute("data-truth"), what="the true footprint drawn")
    x, y, _ = (float(v) for v in canvas.get_attribute("data-truth").split(","))
    assert math.hypot(x - true_pose[0], y - true_pose[1]) < 1
    # the estimate moved by the socket API, the truth stays: the layer shows both apart
    platform.other.set_frm_pltf(int(true_pose[0]) + 1500, int(true_pose[1]), 0)
    wait_for(lambda: platform.control("pose")["estimate"][0] > true_pose[0] + 1000, what="the estimate shifted")
    x, y, _ = (float(v) for v in canvas.get_attribute("data-truth").split(","))
    assert math.hypot(x - true_pose[0], y - true_pose[1]) < 1
    platform.control("overtemp right 90")
    expect_text(truth, "injected faults: overtemp MOTOR_RIGHT 90")
    page.screenshot(path=str(artifacts / "ground-truth.png"))
    # the view option hides the footprint; the GUI never needs the channel: a wrong address is said and ignored
    page.get_by_role("menuitem", name="View", exact=True).click()
    page.get_by_role("menuitem", name="View Options", exact=True).click()
    page.get_by_role("checkbox", name="Show true pose (control channel)").uncheck()
    wait_for(lambda: canvas.get_attribute("data-truth") is None, what="the true footprint hidden")
    page.goto(f"{gateway.url(platform.target)}&control=127.0.0.1:{free_port()}")
    expect_text(truth, "not read")
    expect_text(page.get_by_role("status", name="Connection", exact=True), f"connected to {platform.target}")
    page.goto(f"{gateway.url(platform.target)}&control=192.0.2.1:7000")
    expect_text(truth, "loopback address only")


def test_the_live_layer_draws_the_scan_the_ultrasonic_readings_and_the_path(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    """guide 5.3: the laser scan, the ultrasonic readings and the interpolated path, counted against GET_STATUS
    over the other port; the motion mode combo box offers the guide's seven modes."""
    open_gui(page, gateway, platform.target)
    canvas = page.get_by_role("img", name="Map")
    other = platform.other
    wait_for(lambda: canvas.get_attribute("data-drawn-scan") == str(len(other.get_status().scan)), what="scan drawn")
    assert int(canvas.get_attribute("data-drawn-scan")) > 500
    assert canvas.get_attribute("data-drawn-ultrasonic") == "0"  # not measuring: nothing to draw
    modes = page.get_by_role("combobox", name="Motion mode").locator("option").all_inner_texts()
    assert len(modes) == 7, modes
    init_and_start(page, platform, "Automatic")
    other.start_ultrasonic(0xFFFF)
    wait_for(lambda: canvas.get_attribute("data-drawn-ultrasonic") == "16", what="16 ultrasonic readings drawn")
    assert canvas.get_attribute("data-drawn-path") == "0"
    other.move_to_station("Corridor_05")
    wait_for(lambda: int(canvas.get_attribute("data-drawn-path") or 0) > 1, what="the interpolated path drawn")
