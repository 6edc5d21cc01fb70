"""The GUI in Debian's chromium against the reference server over real sockets (issue 19, "What must hold").

Elements are found by role and accessible name, as a person would; what the GUI did is checked over the
platform's OTHER port with a plain client (clients.pltf_client), never through the GUI itself.
"""

from __future__ import annotations

import json
import math
import re
import time
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

from playwright import sync_api as playwright_sync

from pltf.client import EmergencyState, MotionMode, OperationState, PlatformClient
from tests.gui.conftest import Gateway, Platform, aim, expect_text, open_gui, wait_for
from tests.gui.fakes import BadPlatform, free_port

READY, RUNNING = OperationState.ST_OP_READY, OperationState.ST_OP_RUNNING


def button(page: Any, name: str) -> Any:
    return page.get_by_role("button", name=name, exact=True)


def readout(page: Any, name: str) -> Any:
    return page.get_by_role("status", name=name, exact=True)


def init_and_start(page: Any, platform: Platform, mode: str | None = None) -> None:
    button(page, "Init").click()
    expect_text(readout(page, "System state"), "Ready")
    if mode is not None:
        page.get_by_role("combobox", name="Motion mode").select_option(label=mode)
        expect_text(readout(page, "Motion mode"), mode)
    button(page, "Start").click()
    expect_text(readout(page, "System state"), "Running")
    wait_for(lambda: platform.other.get_status().operation_state == RUNNING, what="Running over the other port")


def pose(client: PlatformClient) -> tuple[int, int, float]:
    s = client.get_status()
    return s.est_x_mm, s.est_y_mm, s.est_angle_mdeg / 1000


def test_open_socket_then_init_and_start_from_the_buttons(
    page: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    page.goto(gateway.url(platform.target))
    expect_text(readout(page, "Connection"), f"connected to {platform.target}")
    # Close Socket, then Socket -> Open Socket again (guide 5.2)
    page.get_by_role("menuitem", name="Socket", exact=True).click()
    page.get_by_role("menuitem", name="Close Socket", exact=True).click()
    expect_text(readout(page, "Connection"), "socket closed")
    page.get_by_role("menuitem", name="Socket", exact=True).click()
    page.get_by_role("menuitem", name="Open Socket", exact=True).click()
    expect_text(readout(page, "Connection"), f"connected to {platform.target}")
    expect_text(readout(page, "System state"), "Not initialized")
    playwright_sync.expect(button(page, "Init")).to_be_enabled()
    playwright_sync.expect(button(page, "Start")).to_be_disabled()
    button(page, "Init").click()
    expect_text(readout(page, "System state"), "Ready")
    assert platform.other.get_status().operation_state == READY
    assert button(page, "Init").is_disabled()
    assert button(page, "Break").is_disabled()
    button(page, "Start").click()
    expect_text(readout(page, "System state"), "Running")
    assert platform.other.get_status().operation_state == RUNNING
    assert button(page, "Start").is_disabled() and button(page, "Break").is_enabled()
    assert page.get_by_role("combobox", name="Motion mode").is_disabled()  # guide 5.6: modes change in Ready only
    page.screenshot(path=str(artifacts / "main-view.png"))


def test_close_socket_leaves_the_operating_mode_alone(page: Any, gateway: Gateway, platform: Platform) -> None:
    open_gui(page, gateway, platform.target)
    init_and_start(page, platform, "Velocity")
    page.get_by_role("menuitem", name="Socket", exact=True).click()
    page.get_by_role("menuitem", name="Close Socket", exact=True).click()
    expect_text(readout(page, "Connection"), "socket closed")
    st = platform.other.get_status()
    assert (st.operation_state, st.motion_mode) == (RUNNING, MotionMode.MODE_MOTION_VEL)
    assert button(page, "Stop").is_disabled()


def test_automatic_and_a_dragged_target_flag_bring_the_platform_there(
    page: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    open_gui(page, gateway, platform.target)
    init_and_start(page, platform, "Automatic")
    x0, y0, _ = pose(platform.other)
    goal = (x0 + 3000, y0 + 500)
    button(page, "Target frame").click()
    canvas = page.get_by_role("img", name="Map")
    wait_for(lambda: canvas.get_attribute("data-flag"), what="the target flag")
    sx, sy = aim(page, x0, y0)
    tx, ty = aim(page, *goal)
    page.mouse.move(sx, sy)
    page.mouse.down()
    page.mouse.move(tx, ty, steps=8)
    page.mouse.up()
    expect_text(page.get_by_role("status", name="Map messages"), "CMD_MOVE_ABS sent")
    fx, fy, _ = (float(v) for v in canvas.get_attribute("data-flag").split(","))
    tolerance = 2 / float(json.loads(canvas.get_attribute("data-camera"))["scale"])  # two pixels of the drag
    assert math.hypot(fx - goal[0], fy - goal[1]) <= tolerance
    wait_for(
        lambda: math.hypot(pose(platform.other)[0] - fx, pose(platform.other)[1] - fy) < 100,
        timeout=30,
        what="the platform at the flag (over the other port)",
    )
    page.screenshot(path=str(artifacts / "automatic-flag.png"))


def test_velocity_mode_from_the_keyboard_moves_and_releasing_stops(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    open_gui(page, gateway, platform.target)
    init_and_start(page, platform, "Velocity")
    x0, y0, _ = pose(platform.other)
    page.get_by_role("img", name="Map").focus()
    page.keyboard.down("ArrowUp")
    wait_for(
        lambda: math.hypot(pose(platform.other)[0] - x0, pose(platform.other)[1] - y0) > 300,
        timeout=15,
        what="the platform moving forward",
    )
    page.keyboard.up("ArrowUp")
    wait_for(lambda: platform.other.get_status().vel_trans_mm_s == 0, timeout=10, what="the commanded velocity 0")
    time.sleep(0.3)
    a = pose(platform.other)
    time.sleep(1.0)  # the watchdog would stop it too, but after 0.5 s simulated: 1 s wall is 5 s simulated
    b = pose(platform.other)
    assert math.hypot(b[0] - a[0], b[1] - a[1]) < 5, (a, b)


def test_an_emergency_stop_shows_within_a_second(
    page: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    open_gui(page, gateway, platform.target)
    button(page, "Init").click()
    expect_text(readout(page, "System state"), "Ready")
    platform.control("estop press")
    expect_text(readout(page, "Emergency state"), "EMERGENCY STOP", timeout=1000)
    assert platform.other.get_status().emergency_state == EmergencyState.ST_EM_ACTIVE
    assert button(page, "Start").is_disabled()
    page.screenshot(path=str(artifacts / "emergency-stop.png"))
    platform.control("estop release")
    expect_text(readout(page, "Emergency state"), re.compile("reset|not active"))


def test_a_parameter_set_in_the_window_reads_back_over_the_socket(
    page: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    open_gui(page, gateway, platform.target)
    page.get_by_role("menuitem", name="Parameter", exact=True).click()
    page.get_by_role("menuitem", name="Platform parameters", exact=True).click()
    page.get_by_role("tab", name="Interpolation", exact=True).click()
    page.get_by_role("row").filter(has_text="IpoTransVel").click()
    value = page.get_by_role("textbox", name="Value IpoTransVel")
    # refused before sending, with the reason (spec/parameters.yaml: 50 .. 1500 mm/s)
    value.fill("5000")
    button(page, "Set").click()
    expect_text(page.get_by_role("status", name="Platform answer"), "outside 50 .. 1500 mm/s")
    assert platform.other.get_pltf_param("IpoTransVel").value == "1000"
    value.fill("800")
    button(page, "Set").click()
    expect_text(page.get_by_role("status", name="Platform answer"), "IpoTransVel = 800")
    assert platform.other.get_pltf_param("IpoTransVel").value == "800"
    page.screenshot(path=str(artifacts / "parameters.png"))


def test_disabling_an_ultrasonic_sensor_in_the_monitor_shows_in_get_status(
    page: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    open_gui(page, gateway, platform.target)
    button(page, "Init").click()
    expect_text(readout(page, "System state"), "Ready")
    page.get_by_role("menuitem", name="View", exact=True).click()
    page.get_by_role("menuitem", name="Hardware Monitor", exact=True).click()
    page.get_by_role("tab", name="USBoard", exact=True).click()
    button(page, "start US").click()
    wait_for(lambda: all(d > 0 for d in platform.other.get_status().us_distance_mm), what="all 16 sensors measuring")
    sensor3 = page.get_by_role("checkbox", name="Sensor 3", exact=True)
    playwright_sync.expect(sensor3).to_be_checked()
    sensor3.uncheck()
    wait_for(lambda: platform.other.get_status().us_distance_mm[2] == 0, what="sensor 3 off in GET_STATUS")
    distances = platform.other.get_status().us_distance_mm
    assert all(d > 0 for i, d in enumerate(distances) if i != 2), distances
    page.screenshot(path=str(artifacts / "hardware-monitor-usboard.png"))


def _document_counts(xml: str) -> dict[str, int]:
    counts: dict[str, int] = {}
    for layer in ET.fromstring(xml).findall("layer"):
        for obj in layer:
            counts[obj.tag] = counts.get(obj.tag, 0) + 1
    return counts


def test_every_map_object_of_get_map_is_drawn(page: Any, gateway: Gateway, platform: Platform) -> None:
    open_gui(page, gateway, platform.target)
    button(page, "Zoom all").click()
    canvas = page.get_by_role("img", name="Map")
    expected = _document_counts(platform.other.get_map().xml)
    roadmap = ET.fromstring(platform.other.get_roadmap().xml)
    expected["station"] = len(roadmap.findall("stations/station"))
    expected["edge"] = len(roadmap.findall("edges/edge"))
    assert expected["line"] > 0 and expected["station"] > 0

    def drawn() -> dict[str, int]:
        return {k: int(canvas.get_attribute(f"data-drawn-{k}") or 0) for k in expected}

    wait_for(lambda: drawn() == expected, what=f"drawn == {expected}")
    assert canvas.get_attribute("data-complete") == "true"
    summary = page.locator("#map-summary").text_content()
    assert "Lines: 20/20" in summary and "Stations: 18/18" in summary


def test_switching_the_language_changes_the_labels(
    page: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    open_gui(page, gateway, platform.target)
    page.get_by_role("menuitem", name="View", exact=True).click()
    page.get_by_role("menuitem", name="View Options", exact=True).click()
    page.get_by_role("radio", name="German", exact=True).check()
    expect_text(page.get_by_role("status", name="Systemzustand"), "Nicht initialisiert")
    expect_text(page.get_by_role("status", name="Verbindung"), f"verbunden mit {platform.target}")  # the gateway's
    assert button(page, "Initialisieren").is_enabled()
    page.get_by_role("menuitem", name="Ansicht", exact=True).click()
    assert page.get_by_role("menuitem", name="Ansichtsoptionen", exact=True).is_visible()
    page.keyboard.press("Escape")
    assert page.get_by_role("combobox", name="Bewegungsmodus").count() == 1
    assert button(page, "Init").count() == 0
    page.screenshot(path=str(artifacts / "german.png"))
    page.get_by_role("radio", name="Englisch", exact=True).check()
    expect_text(page.get_by_role("status", name="System state"), "Not initialized")


def test_each_fault_shows_its_message_and_the_gui_keeps_running(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    status = readout(page, "Connection")
    cases = [
        (f"127.0.0.1:{free_port()}", "refused the connection"),
        ("no-such-platform.invalid:10000", "cannot be reached"),
    ]
    for target, text in cases:
        open_gui(page, gateway, target, connected=False)
        expect_text(status, text)
        expect_text(status, re.compile(f"{re.escape(target)}|reconnecting"))
    misbehaving = [("silent", "stopped answering"), ("garbage", "malformed reply"), ("drop", "closed the connection")]
    for behaviour, text in misbehaving:
        with BadPlatform(behaviour) as bad:
            open_gui(page, gateway, bad.target, connected=False)
            expect_text(status, text)
    # the port already has a client (erratum E-WIRE-007): the platform turns the GUI away
    with PlatformClient("127.0.0.1", platform.ports[0], timeout=5.0) as first:
        first.get_status()
        open_gui(page, gateway, platform.target, connected=False)
        expect_text(status, "its port already has a client")
    # ... and once the port is free again the GUI reconnects by itself
    expect_text(status, f"connected to {platform.target}", timeout=20_000)
    expect_text(readout(page, "System state"), "Not initialized")


def test_the_gateway_s_messages_follow_the_language(page: Any, gateway: Gateway, platform: Platform) -> None:
    page.goto(gateway.url(f"127.0.0.1:{free_port()}"))
    page.evaluate("localStorage.setItem('pltf.lang', 'de')")
    status = page.get_by_role("status", name="Verbindung")
    refused = f"127.0.0.1:{free_port()}"
    open_gui(page, gateway, refused, connected=False)
    expect_text(status, f"{refused} hat die Verbindung abgelehnt")
    expect_text(status, "neuer Versuch in")  # the retry repeats its failure, in German too
    for behaviour, text in [
        ("silent", "antwortet nicht mehr: keine Antwort seit 2 s"),
        ("garbage", "fehlerhafte Antwort"),
    ]:
        with BadPlatform(behaviour) as bad:
            open_gui(page, gateway, bad.target, connected=False)
            expect_text(status, text)
    with PlatformClient("127.0.0.1", platform.ports[0], timeout=5.0) as first:
        first.get_status()
        open_gui(page, gateway, platform.target, connected=False)
        expect_text(status, "sein Port hat schon einen Client")
    expect_text(status, f"verbunden mit {platform.target}", timeout=20_000)
    # switched back without a reload: the same event in English
    page.get_by_role("menuitem", name="Ansicht", exact=True).click()
    page.get_by_role("menuitem", name="Ansichtsoptionen", exact=True).click()
    page.get_by_role("radio", name="Englisch", exact=True).check()
    expect_text(readout(page, "Connection"), f"connected to {platform.target}")


def test_two_tabs_share_the_one_connection_and_the_second_port_stays_free(
    browser: Any, page: Any, gateway: Gateway, platform: Platform
) -> None:
    open_gui(page, gateway, platform.target)
    second = browser.new_page()
    try:
        open_gui(second, gateway, platform.target)  # a second connection to the port would be turned away
        button(page, "Init").click()
        expect_text(readout(second, "System state"), "Ready")
        assert platform.other.get_status().operation_state == READY  # the guide's second port is the user's
    finally:
        second.close()


def test_shifting_the_platform_by_drag_and_drop_sets_the_estimate(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    open_gui(page, gateway, platform.target)
    x0, y0, _ = pose(platform.other)
    button(page, "Shift platform").click()
    sx, sy = aim(page, x0, y0)
    tx, ty = aim(page, x0 + 1000, y0 - 400)
    page.mouse.move(sx, sy)
    page.mouse.down()
    page.mouse.move(tx, ty, steps=6)
    page.mouse.up()
    expect_text(page.get_by_role("status", name="Map messages"), "CMD_SET_FRM_PLTF sent")
    scale = float(json.loads(page.get_by_role("img", name="Map").get_attribute("data-camera"))["scale"])

    def off() -> float:
        x, y, _ = pose(platform.other)
        return math.hypot(x - (x0 + 1000), y - (y0 - 400))

    wait_for(lambda: off() <= 2 / scale, what="the estimate where the platform was dropped (over the other port)")


def test_open_socket_at_lists_the_known_addresses_and_keeps_a_new_one(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    open_gui(page, gateway, f"127.0.0.1:{free_port()}", connected=False)
    page.get_by_role("menuitem", name="Socket", exact=True).click()
    page.get_by_role("menuitem", name="Open Socket At", exact=True).click()
    dialog = page.get_by_role("dialog", name="Open Socket At")
    assert "127.0.0.1:10000" in dialog.get_by_role("combobox", name="Server").inner_text()
    dialog.get_by_role("textbox", name="Address (HOST:PORT)").fill(platform.target)
    dialog.get_by_role("button", name="Connect", exact=True).click()
    expect_text(readout(page, "Connection"), f"connected to {platform.target}")
    assert platform.target in gateway.ini.read_text(encoding="utf-8")
    assert f"target={platform.target.replace(':', '%3A')}" in page.url
