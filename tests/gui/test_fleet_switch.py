"""The fleet view when the selected platform changes (issue 30's GUI, three faults found after it): each platform is
polled by one GET_STATUS stream (counted on the wire, through ``pltf proxy`` in front of each platform), drawn with
its own footprint (pixels of the canvas where its parameters put its outline), and an open editor's document
survives a switch (erratum E-GUI-012). ``pltf serve --fleet`` with three platforms, ``pltf gui --fleet``, Debian's
chromium.
"""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from pltf.client import PlatformClient
from pltf.gui.launch import GatewayProcess
from pltf.proxy.session import open_session
from pltf.proxy.tap import FRAME
from tests.gui.conftest import expect_text, settled_view, wait_for
from tests.gui.test_fleet_view import playwright_expect
from tests.reference_server.test_fleet_conformance import FleetProcess

REPO = Path(__file__).resolve().parents[2]
NAMES = ("p00", "p01", "p02")  # FleetProcess: along the corridor at x = 2000 + 2500 k, y = 10000, angle 0
LONG = {"PltfLength": 1600, "DistWheels": 900, "DistPltfCenterToWheelAxis": 100}  # p02's geometry (guide 5.9)
COLOURS = {"p00": (0x00, 0x72, 0xB2), "p01": (0xD5, 0x5E, 0x00), "p02": (0x00, 0x9E, 0x73)}  # session/fleet.ts


class Fleet:
    def __init__(self, srv: FleetProcess) -> None:
        self.srv = srv
        self.first = {n: f"127.0.0.1:{srv.ports[n][0]}" for n in NAMES}
        self.other = {n: PlatformClient("127.0.0.1", srv.ports[n][1], timeout=10.0) for n in NAMES}

    def gui_file(self, path: Path, ports: dict[str, int]) -> Path:
        """A fleet file for ``pltf gui --fleet``: the platforms' names with ``ports`` (the fleet's, or proxies')."""
        doc = {"platforms": [{"name": n, "ports": [ports[n]]} for n in NAMES]}
        path.write_text(yaml.safe_dump(doc), encoding="utf-8")
        return path

    def close(self) -> None:
        for c in self.other.values():
            c.close()
        self.srv.stop()


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Fleet]:
    tmp = tmp_path_factory.mktemp("fleet-switch")
    f = Fleet(FleetProcess(tmp, len(NAMES), None, "--no-hardware", time_scale=5.0))
    try:
        for key, value in LONG.items():  # p02 is a bigger platform than the others (its own parameters)
            f.other["p02"].set_pltf_param(key, str(value))
        wait_for(
            lambda: float(f.other["p02"].get_pltf_param("PltfLength").value) == LONG["PltfLength"],
            what="p02's PltfLength",
        )
        yield f
    finally:
        f.close()


@pytest.fixture(scope="module")
def gui(fleet: Fleet, tmp_path_factory: pytest.TempPathFactory) -> Iterator[GatewayProcess]:
    tmp = tmp_path_factory.mktemp("fleet-switch-gui")
    ports = {n: fleet.srv.ports[n][0] for n in NAMES}
    args = ("--fleet", str(fleet.gui_file(tmp / "gui-fleet.yaml", ports)))
    with GatewayProcess(tmp / "Network.ini", target=None, allow_any_target=False, args=args) as gw:
        yield gw


def _url(base: str, targets: list[str]) -> str:
    return f"{base}/?" + "&".join(f"target={t}" for t in targets)


def _line(page: Any, name: str) -> Any:
    return page.locator(f".fleet-line[data-name={name}]")


def _all_connected(page: Any) -> None:
    for n in NAMES:
        playwright_expect(_line(page, n)).to_have_attribute("data-connected", "true")


def _select(page: Any, name: str, target: str) -> None:
    _line(page, name).click()
    playwright_expect(_line(page, name)).to_have_attribute("aria-pressed", "true")
    expect_text(page.get_by_role("status", name="Connection"), f"connected to {target}")


def messages(page: Any) -> Any:
    return page.get_by_role("status", name="Messages", exact=True)


# ------------------------------------------------------------------------------------ 1: one poll stream each

STATUS_HZ = 20  # session/session.ts DEFAULT_STATUS_HZ: the selected platform's (the panels') stream
WATCH_HZ = 5  # panels/fleet.ts: a watched platform's stream
WINDOW = 6.0  # s of wire counted per selection
# A poller asks again one period after its last request (session.ts), so one stream sends at most hz requests a
# second; load only slows it. The slack covers a request that waited in the browser or the gateway and went out
# just inside the window (two streams on the selected platform: 25 a second, 150 in the window, over 20 * 6 * 1.1 + 3)
SLACK = 1.1


class Proxies:
    """``pltf proxy --record`` in front of each platform's first port: the GET_STATUS requests each one receives,
    counted from its recording once the proxies have stopped."""

    def __init__(self, fleet: Fleet, tmp: Path) -> None:
        self.files = {n: tmp / f"{n}.jsonl" for n in NAMES}
        self.logs = {n: tmp / f"{n}.log" for n in NAMES}
        self.procs: dict[str, subprocess.Popen[bytes]] = {}
        for n in NAMES:
            cmd = [sys.executable, "-m", "pltf.cli.main", "proxy", "--listen", "127.0.0.1:0", "--quiet"]
            cmd += ["--target", fleet.first[n], "--record", str(self.files[n])]
            with self.logs[n].open("wb") as log:
                self.procs[n] = subprocess.Popen(cmd, cwd=REPO, stdout=log, stderr=subprocess.STDOUT)
        self.ports = {n: int(wait_for(lambda n=n: self._port(n), what=f"{n}'s proxy listening")) for n in NAMES}

    def _port(self, name: str) -> int | None:
        if self.procs[name].poll() is not None:
            raise AssertionError(f"{name}'s proxy exited: {self.logs[name].read_text()}")
        found = re.search(r"listening at [\d.]+:(\d+)", self.logs[name].read_text())
        return int(found.group(1)) if found else None

    def stop(self) -> None:
        for proc in self.procs.values():
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
        for proc in self.procs.values():
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()

    def status_requests(self, name: str, since: float, until: float) -> int:
        """GET_STATUS requests the platform received between two wall-clock times (decoded from the recorded
        bytes, with the recording's times)."""
        return sum(
            rec.kind == FRAME
            and rec.direction == "request"
            and since <= rec.time < until
            and rec.telegram is not None
            and rec.telegram.NAME == "CMD_GET_STATUS"
            for rec in open_session(self.files[name]).records()
        )


def test_one_get_status_stream_per_platform_before_and_after_a_switch(page: Any, fleet: Fleet, tmp_path: Path) -> None:
    proxies = Proxies(fleet, tmp_path)
    try:
        args = ("--fleet", str(fleet.gui_file(tmp_path / "gui-fleet.yaml", proxies.ports)))
        with GatewayProcess(tmp_path / "Network.ini", target=None, allow_any_target=False, args=args) as gw:
            targets = [f"127.0.0.1:{proxies.ports[n]}" for n in NAMES]
            page.goto(_url(gw.base, targets), timeout=30_000)
            _all_connected(page)
            time.sleep(1.0)  # the connections' first requests (parameters, documents) are behind
            windows = {"p00": (time.time(), time.time() + WINDOW)}
            time.sleep(WINDOW)
            _select(page, "p01", targets[1])
            _all_connected(page)
            time.sleep(1.0)
            windows["p01"] = (time.time(), time.time() + WINDOW)
            time.sleep(WINDOW)
            page.close()
    finally:
        proxies.stop()
    for selected, (t0, t1) in windows.items():
        got = {n: proxies.status_requests(n, t0, t1) for n in NAMES}
        for n, count in got.items():
            hz = STATUS_HZ if n == selected else WATCH_HZ
            assert count <= hz * WINDOW * SLACK + 3, (
                f"{selected} selected: {n} received {count} GET_STATUS in {WINDOW:g} s, more than one stream of "
                f"{hz} Hz sends: {got}"
            )
            assert count > 0, f"{selected} selected: {n} was not polled at all: {got}"


# ------------------------------------------------------------------------------------- 2: its own footprint

_INK = """([points, rgb]) => {
  const canvas = document.querySelector("canvas.map-canvas");
  const ctx = canvas.getContext("2d");
  const dpr = window.devicePixelRatio || 1;
  return points.map(([x, y]) => {
    const d = ctx.getImageData(Math.round(x * dpr) - 3, Math.round(y * dpr) - 3, 7, 7).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) {
      const near = Math.abs(d[i] - rgb[0]) + Math.abs(d[i + 1] - rgb[1]) + Math.abs(d[i + 2] - rgb[2]) < 90;
      n += near && d[i + 3] > 128 ? 1 : 0;
    }
    return n;
  });
}"""


def _outline_points(centre: tuple[float, float], rear: float, front: float, half: float) -> list[tuple[float, float]]:
    """World points on a footprint's front and rear edges and its right side, off the heading line and away from
    the name label (drawn above and right of the centre); the platforms face +x (angle 0)."""
    x, y = centre
    return [(x + front, y - half / 2), (x + rear, y - half / 2), (x + (rear + front) / 2, y - half)]


def _ink(page: Any, world: list[tuple[float, float]], rgb: tuple[int, int, int]) -> list[int]:
    """Pixels of colour ``rgb`` around each world point on the canvas as drawn now (a 7 x 7 px square each)."""
    canvas = page.locator("canvas.map-canvas")
    cam = json.loads(canvas.get_attribute("data-camera"))
    px = [
        ((wx - cam["cx"]) * cam["scale"] + cam["width"] / 2, (cam["cy"] - wy) * cam["scale"] + cam["height"] / 2)
        for wx, wy in world
    ]
    got: list[int] = page.evaluate(_INK, [px, list(rgb)])
    return got


def _zoom_on(page: Any, x: float, y: float, scale: float) -> None:
    page.evaluate(
        "([x, y, s]) => { const m = window.pltf.map; m.setCamera({ ...m.cam, cx: x, cy: y, scale: s }); m.render(); }",
        [x, y, scale],
    )


def _drawn(page: Any) -> set[str]:
    """The platforms data-fleet says are drawn (a pose known)."""
    text = page.locator("canvas.map-canvas").get_attribute("data-fleet") or ""
    return {name for name, at in re.findall(r"\*?([\w-]+)@([^;]+)", text) if at != "-"}


def _outline_of(page: Any, name: str) -> tuple[float, ...] | None:
    """data-fleet's footprint of one platform as drawn: (rear, front, half width), or None."""
    text = page.locator("canvas.map-canvas").get_attribute("data-fleet") or ""
    found = re.search(rf"\*?{name}@[^;/]+/(-?\d+),(-?\d+),(-?\d+)", text)
    return None if found is None else tuple(float(v) for v in found.groups())


def test_each_platform_is_drawn_with_its_own_footprint(
    page: Any, fleet: Fleet, gui: GatewayProcess, artifacts: Path
) -> None:
    """p02 is 1600 mm long and 1010 mm wide (its parameters), p00 and p01 650 x 540 (the defaults): with p00
    selected, p02's body is drawn in its colour along its own outline, and none of it where the default outline
    would put it; with p02 selected, p00 (watched now) is drawn along its own."""
    long = (-LONG["DistPltfCenterToWheelAxis"] - LONG["PltfLength"] / 2, -100 + LONG["PltfLength"] / 2)
    big = (*long, (LONG["DistWheels"] + 110) / 2)
    default = (-425.0, 225.0, 270.0)
    start = {n: (2000 + 2500 * k, 10000) for k, n in enumerate(NAMES)}
    page.goto(_url(gui.base, [fleet.first[n] for n in NAMES]), timeout=30_000)
    _all_connected(page)
    wait_for(lambda: _drawn(page) == set(NAMES), what="three bodies drawn")
    settled_view(page)

    def inked(name: str, outline: tuple[float, float, float]) -> list[int]:
        _zoom_on(page, *start[name], 0.1)
        return _ink(page, _outline_points(start[name], *outline), COLOURS[name])

    try:
        wait_for(lambda: all(n > 0 for n in inked("p02", big)), timeout=10, what="p02's own outline in its colour")
    finally:
        page.screenshot(path=str(artifacts / "fleet-footprints.png"))
    assert inked("p02", default) == [0, 0, 0]  # nothing where the default outline would be
    assert _outline_of(page, "p02") == big

    _select(page, "p02", fleet.first["p02"])
    wait_for(lambda: all(n > 0 for n in inked("p00", default)), timeout=10, what="p00's own outline in its colour")
    # nothing of p00's blue along p02's outline: neither p00 drawn with p02's footprint (a body's own not read yet is
    # the default one) nor the selected body (#1565c0, within the colour's tolerance) at p00's last pose
    canvas = page.locator("canvas.map-canvas")
    seen = {k: canvas.get_attribute(f"data-{k}") for k in ("fleet", "platform")}
    assert inked("p00", big) == [0, 0, 0], seen
    wait_for(lambda: _outline_of(page, "p02") == big, what="the selected p02 with its own footprint")


# ------------------------------------------------------------------------------------ 3: the editor's document


def _objects(client: PlatformClient) -> list[tuple[str, dict[str, str]]]:
    root = ET.fromstring(client.get_map().xml)
    return [(o.tag, dict(o.attrib)) for layer in root.findall("layer") for o in layer]


def test_an_open_map_editor_keeps_its_document_over_a_switch_and_asks_before_sending_it_elsewhere(
    page: Any, fleet: Fleet, gui: GatewayProcess
) -> None:
    """Erratum E-GUI-012: p00's map loaded and edited (a line added), then p01 selected: the editor stays open
    with the edit unsaved and says whose map it holds; Send asks first (Cancel: p01's map unchanged over its other
    port), then sends it to p01, whose map it is from then on; p00's map is never touched."""
    maps = {n: _objects(fleet.other[n]) for n in ("p00", "p01")}
    page.goto(_url(gui.base, [fleet.first[n] for n in NAMES]), timeout=30_000)
    _all_connected(page)
    page.get_by_role("menuitem", name="Edit", exact=True).click()
    page.get_by_role("menuitem", name="Edit Map", exact=True).click()
    page.get_by_role("button", name="Load from platform", exact=True).click()
    expect_text(messages(page), "Map loaded into the editor")
    state = page.locator("output.edit-state")
    wait_for(lambda: state.get_attribute("data-objects") == str(len(maps["p00"])), what="p00's map in the editor")
    heading = page.locator("#pane-edit-map .edit-owner")
    expect_text(heading, "Map of p00")
    page.get_by_role("button", name="Add a line", exact=True).click()
    _, box = settled_view(page)
    page.mouse.move(box["x"] + box["width"] * 0.37, box["y"] + box["height"] * 0.41)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] * 0.63, box["y"] + box["height"] * 0.44, steps=5)
    page.mouse.up()
    edited = len(maps["p00"]) + 1
    wait_for(lambda: state.get_attribute("data-objects") == str(edited), what="the added line")

    _select(page, "p01", fleet.first["p01"])
    expect_text(heading, "p00's document; p01 is selected")
    playwright_expect(page.locator("#pane-edit-map")).to_be_visible()
    assert state.get_attribute("data-objects") == str(edited) and state.get_attribute("data-dirty") == "true"
    canvas = page.get_by_role("img", name="Map")
    assert canvas.get_attribute("data-drawn-line") is not None

    send = page.locator("#pane-edit-map").get_by_role("button", name="Send to platform", exact=True)
    ask = page.get_by_role("dialog", name="Send to another platform?")
    send.click()
    expect_text(ask, "This document is p00's (loaded from it or sent to it). Send it to p01")
    ask.get_by_role("button", name="Cancel", exact=True).click()
    time.sleep(1.0)  # a CMD_SET_MAP sent anyway would be active by now (guide 6.1: no reply to wait for)
    assert _objects(fleet.other["p01"]) == maps["p01"]
    assert state.get_attribute("data-dirty") == "true"

    send.click()
    ask.get_by_role("button", name="Send to platform", exact=True).click()
    expect_text(messages(page), "Map sent to the platform and active")
    wait_for(lambda: len(_objects(fleet.other["p01"])) == edited, what="the edited map on p01")
    expect_text(heading, "Map of p01")
    assert _objects(fleet.other["p00"]) == maps["p00"]
