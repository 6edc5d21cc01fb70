"""The GUI shows the fleet (issue 30): ``pltf gui --fleet FILE`` against ``pltf serve --fleet`` with three
platforms, in Debian's chromium. Every platform is drawn on the map (the canvas's ``data-fleet`` and its
accessible summary) and has its status line; the second one selected and driven (Init, Automatic, Start, Move
relative) is the only one that moves or changes state, checked over TCP on each platform's OTHER port
(GET_POSITION, GET_STATUS); a click on a body on the map selects it. The gateway lets the page open the fleet's
platforms and nothing else (issue 33's doors: no --allow-any-target here).
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from pltf.client import OperationState, PlatformClient
from pltf.gui.launch import GatewayProcess
from tests.gui.conftest import PATIENCE, aim, expect_text, wait_for
from tests.gui.fakes import Recorder, Tab, run
from tests.gui.test_app import button, readout
from tests.reference_server.test_fleet_conformance import FleetProcess

REPO = Path(__file__).resolve().parents[2]
NAMES = ("p00", "p01", "p02")  # FleetProcess: along the corridor at x = 2000 + 2500 k, y = 10000, angle 0
STEP = 1000  # mm: the second platform's Move relative


class Fleet:
    def __init__(self, srv: FleetProcess, gui: GatewayProcess) -> None:
        self.srv = srv
        self.gui = gui
        self.targets = [f"127.0.0.1:{srv.ports[n][0]}" for n in NAMES]
        self.other = {n: PlatformClient("127.0.0.1", srv.ports[n][1], timeout=10.0) for n in NAMES}

    def url(self) -> str:
        return f"{self.gui.base}/?" + "&".join(f"target={t}" for t in self.targets)

    def position(self, name: str) -> tuple[int, int]:
        p = self.other[name].get_position()
        return p.x_mm, p.y_mm


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Fleet]:
    tmp = tmp_path_factory.mktemp("fleet-view")
    srv = FleetProcess(tmp, len(NAMES), None, "--no-hardware", time_scale=5.0)
    try:
        # the GUI's fleet file: the same platforms, with the ports the fleet took (its own file says 0)
        gui_file = tmp / "gui-fleet.yaml"
        doc = {"platforms": [{"name": n, "ports": list(srv.ports[n])} for n in NAMES]}
        gui_file.write_text(yaml.safe_dump(doc), encoding="utf-8")
        with GatewayProcess(
            tmp / "Network.ini", target=None, allow_any_target=False, args=("--fleet", str(gui_file))
        ) as gui:
            f = Fleet(srv, gui)
            try:
                yield f
            finally:
                for c in f.other.values():
                    c.close()
    finally:
        srv.stop()


def _line(page: Any, name: str) -> Any:
    return page.locator(f".fleet-line[data-name={name}]")


def _bodies(page: Any) -> dict[str, tuple[float, float]]:
    """The canvas's data-fleet: name -> (x, y) mm of every platform drawn."""
    text = page.locator("canvas.map-canvas").get_attribute("data-fleet") or ""
    found = re.findall(r"\*?([\w-]+)@(-?\d+),(-?\d+),", text)
    return {name: (float(x), float(y)) for name, x, y in found}


def test_every_platform_drawn_and_listed_and_only_the_selected_one_driven(page: Any, fleet: Fleet) -> None:
    page.goto(fleet.url(), timeout=30_000)
    start = {n: fleet.position(n) for n in NAMES}
    # three status lines, each with its platform's own state over its own connection
    for n in NAMES:
        playwright_expect(_line(page, n)).to_have_attribute("data-connected", "true")
        expect_text(_line(page, n), re.compile(rf"^{n}.*Not initialized.*x {start[n][0]} mm.*connected$"))
    # all three drawn on the map, where they are
    drawn = wait_for(lambda: _bodies(page) if len(_bodies(page)) == 3 else None, what="three bodies in data-fleet")
    for n in NAMES:
        assert math.dist(drawn[n], start[n]) < 50, (n, drawn[n], start[n])
    expect_text(page.locator("#map-summary"), re.compile(r"Platforms: p00 at .*\(selected\), p01 at .*, p02 at "))
    # select the second by its status line: the panels now talk to it alone
    _line(page, "p01").click()
    playwright_expect(_line(page, "p01")).to_have_attribute("aria-pressed", "true")
    playwright_expect(_line(page, "p00")).to_have_attribute("aria-pressed", "false")
    expect_text(readout(page, "Connection"), f"connected to {fleet.targets[1]}")
    button(page, "Init").click()
    expect_text(readout(page, "System state"), "Ready")
    page.get_by_role("combobox", name="Motion mode").select_option(label="Automatic")
    expect_text(readout(page, "Motion mode"), "Automatic")
    button(page, "Start").click()
    wait_for(lambda: fleet.other["p01"].get_status().operation_state == OperationState.ST_OP_RUNNING, what="Running")
    page.get_by_role("spinbutton", name="Relative X (mm)").fill(str(STEP))
    page.get_by_role("button", name="Move relative", exact=True).click()
    goal = (start["p01"][0] + STEP, start["p01"][1])
    wait_for(lambda: math.dist(fleet.position("p01"), goal) < 100, timeout=40, what=f"p01 at {goal} (GET_POSITION)")
    expect_text(_line(page, "p01"), re.compile(r"Running.*Automatic"))
    # the others got no command: where they were, still not initialized
    for n in ("p00", "p02"):
        assert math.dist(fleet.position(n), start[n]) < 5, (n, fleet.position(n), start[n])
        assert fleet.other[n].get_status().operation_state == OperationState.ST_OP_NOT_INITIALIZED, n
        expect_text(_line(page, n), "Not initialized")
    # a click on the first platform's body on the map selects it
    page.get_by_role("button", name="Pan", exact=True).click()
    sx, sy = aim(page, *start["p00"])
    page.mouse.click(sx, sy)
    playwright_expect(_line(page, "p00")).to_have_attribute("aria-pressed", "true")
    expect_text(readout(page, "Connection"), f"connected to {fleet.targets[0]}")
    expect_text(readout(page, "System state"), "Not initialized")


def test_the_gateway_opens_the_fleet_and_nothing_else(fleet: Fleet) -> None:
    async def first_event(target: str) -> dict[str, object]:
        tab = await Tab.open(fleet.gui.base, target)
        await tab.op("open")
        event = await tab.event("target_refused" if target not in fleet.targets else "connected")
        await tab.close()
        return event

    with Recorder() as outsider:
        refused = run(lambda: first_event(outsider.target))
        assert "not on this GUI's list" in str(refused["message"])
        assert outsider.connects == 0
    assert run(lambda: first_event(fleet.targets[2]))["event"] == "connected"


def test_a_fleet_file_without_its_ports_is_one_line_and_exit_2(tmp_path: Path) -> None:
    bad = tmp_path / "fleet.yaml"
    bad.write_text("platforms:\n  - {name: alpha, ports: [0, 0]}\n", encoding="utf-8")
    run = subprocess.run(
        [sys.executable, "-m", "pltf.cli.main", "gui", "--fleet", str(bad), "--listen", "127.0.0.1:0"],
        cwd=REPO,
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        f"pltf gui: error: fleet file {bad}: platform 'alpha' has port 0 (any free port): the GUI needs the port "
        "it took; give its port in the file, or --target HOST:PORT per platform"
    ]


def playwright_expect(locator: Any) -> Any:
    """Playwright's expect with the browser tests' patience (its own default, 5 s, is short on a loaded machine)."""
    from playwright import sync_api

    sync_api.expect.set_options(timeout=PATIENCE * 1000)
    return sync_api.expect(locator)
