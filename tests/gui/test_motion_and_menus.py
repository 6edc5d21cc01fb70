"""Operation, motion and the menus in Debian's chromium against the reference server (issue 19, guide 4.2, 5.2,
5.6): the target station picker and MOVE_REL in Automatic, Break / Continue / Stop, Shutdown Platform behind its
confirmation, the wire inspector. What the GUI did is checked over the platform's OTHER port.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

from pltf.client import OperationState, PlatformClient
from pltf.client.errors import PlatformError
from tests.gui.conftest import Gateway, Platform, expect_text, open_gui, wait_for
from tests.gui.test_app import button, init_and_start, pose, readout

CORRIDOR_01 = (5000, 10000)  # fixtures/roadmaps/office.rm; the platform starts at (2000, 10000)


def test_the_target_station_picker_and_move_relative_drive_the_platform(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    open_gui(page, gateway, platform.target)
    init_and_start(page, platform, "Automatic")
    controls = page
    controls.get_by_role("combobox", name="Target station").select_option("Corridor_01")
    controls.get_by_role("button", name="Move to station", exact=True).click()
    wait_for(
        lambda: math.hypot(pose(platform.other)[0] - CORRIDOR_01[0], pose(platform.other)[1] - CORRIDOR_01[1]) < 100,
        timeout=30,
        what="the platform at Corridor_01 (over the other port)",
    )
    wait_for(lambda: platform.other.get_status().target_reached, what="target reached")
    x0, y0, a0 = pose(platform.other)
    controls.get_by_role("spinbutton", name="Relative X (mm)").fill("-1000")
    controls.get_by_role("button", name="Move relative", exact=True).click()
    ahead = (x0 - 1000 * math.cos(math.radians(a0)), y0 - 1000 * math.sin(math.radians(a0)))
    wait_for(
        lambda: math.hypot(pose(platform.other)[0] - ahead[0], pose(platform.other)[1] - ahead[1]) < 100,
        timeout=30,
        what=f"the platform 1 m back at {ahead}",
    )


def test_break_continue_and_stop_follow_the_state_chart(page: Any, gateway: Gateway, platform: Platform) -> None:
    open_gui(page, gateway, platform.target)
    init_and_start(page, platform, "Velocity")
    button(page, "Break").click()
    wait_for(lambda: platform.other.get_status().operation_state == OperationState.ST_OP_BREAKED, what="Break")
    expect_text(readout(page, "System state"), re.compile("Break", re.I))
    assert button(page, "Continue").is_enabled() and button(page, "Break").is_disabled()
    button(page, "Continue").click()
    wait_for(lambda: platform.other.get_status().operation_state == OperationState.ST_OP_RUNNING, what="Running")
    button(page, "Stop").click()
    wait_for(lambda: platform.other.get_status().operation_state == OperationState.ST_OP_READY, what="Ready")
    expect_text(readout(page, "System state"), "Ready")
    assert button(page, "Start").is_enabled() and button(page, "Stop").is_disabled()


def test_the_wire_inspector_shows_every_telegram_decoded(
    page: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    open_gui(page, gateway, platform.target)
    page.get_by_role("menuitem", name="View", exact=True).click()
    page.get_by_role("menuitem", name="Wire Inspector", exact=True).click()
    log = page.get_by_role("log", name="Wire Inspector")
    hide = page.get_by_role("checkbox", name=re.compile("^Hide polling"))
    hide.uncheck()
    expect_text(log, "<- CMD_GET_STATUS cmd_x=")
    hide.check()
    button(page, "Init").click()
    expect_text(log, "-> CMD_CONNECT_TO_PLTF")
    expect_text(log, "-> CMD_INIT_PLTF")
    assert "CMD_GET_STATUS" not in log.inner_text()
    page.screenshot(path=str(artifacts / "wire-inspector.png"))
    # texts for a person: the parameter list's first key as the platform sent it, not in hex
    first = platform.other.get_pltf_param_vec().parameters[0].key
    expect_text(
        log,
        f'<- CMD_GET_PLTF_PARAM_VEC parameters=[{len(platform.other.get_pltf_param_vec().parameters)}: {{key="{first}"',
    )


def test_shutdown_platform_asks_first_and_then_sends_cmd_exit(page: Any, gateway: Gateway, platform: Platform) -> None:
    open_gui(page, gateway, platform.target)
    # every text the Messages line shows: once the platform has gone, a poll's "not sent" may replace the
    # "CMD_EXIT sent" notice before a loaded machine's check reads it
    page.evaluate(
        """() => { const el = document.querySelector('[aria-label="Messages"]'); window.__said = [];
        new MutationObserver(() => window.__said.push(el.textContent)).observe(el,
        { childList: true, characterData: true, subtree: true }); }"""
    )
    for answer in ("Cancel", "Shutdown Platform"):
        page.get_by_role("menuitem", name="Socket", exact=True).click()
        page.get_by_role("menuitem", name="Shutdown Platform", exact=True).click()
        dialog = page.get_by_role("dialog", name="Shutdown Platform")
        expect_text(dialog, "CMD_EXIT")
        dialog.get_by_role("button", name=answer, exact=True).click()
        if answer == "Cancel":
            assert platform.other.get_status().operation_state == OperationState.ST_OP_NOT_INITIALIZED
    wait_for(lambda: any("CMD_EXIT sent" in m for m in page.evaluate("window.__said")), what="CMD_EXIT sent")

    def gone() -> bool:
        try:
            with PlatformClient("127.0.0.1", platform.ports[1], timeout=1.0) as c:
                c.get_status()
        except (OSError, PlatformError):
            return True
        return False

    platform.close()  # the fixture's own client on the other port
    wait_for(gone, timeout=15, what="the platform shut down")
    expect_text(readout(page, "Connection"), re.compile("refused|closed|dropped"))
