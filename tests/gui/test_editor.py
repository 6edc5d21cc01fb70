"""The map editor (issue 20) in Debian's chromium against the reference server: what the editor sent is checked
over the platform's OTHER port with a plain client, never through the GUI itself."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

from tests.gui.conftest import Gateway, Platform, aim, expect_text, open_gui, settled_view, wait_for


def _objects(xml: str | bytes) -> list[tuple[str, dict[str, str], list[tuple[str, dict[str, str]]]]]:
    """Every object of a map document: its tag, attributes and children (tag, attributes), in order."""
    return [
        (o.tag, dict(o.attrib), [(c.tag, dict(c.attrib)) for c in o])
        for layer in ET.fromstring(xml).findall("layer")
        for o in layer
    ]


def _open_editor(page: Any, gateway: Gateway, platform: Platform) -> Any:
    open_gui(page, gateway, platform.target)
    page.get_by_role("menuitem", name="Edit", exact=True).click()
    page.get_by_role("menuitem", name="Edit Map", exact=True).click()
    page.get_by_role("button", name="Load from platform", exact=True).click()
    expect_text(page.get_by_role("status", name="Messages", exact=True), "Map loaded into the editor")
    return page.locator("output.edit-state")


def _sent(platform: Platform, before: str | bytes) -> str | bytes:
    got: str | bytes = wait_for(lambda: (x := platform.other.get_map().xml) != before and x, what="the map sent")
    return got


def test_round_trip_add_a_line_and_undo(page: Any, gateway: Gateway, platform: Platform) -> None:
    original = platform.other.get_map().xml
    objects = _objects(original)
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: state.get_attribute("data-objects") == str(len(objects)), what="the loaded map")

    # draw a line by dragging, send it: GET_MAP over the other port has it where it was drawn (10 mm grid)
    page.get_by_role("button", name="Add a line", exact=True).click()
    cam, box = settled_view(page)
    s0, s1 = (box["width"] * 0.37, box["height"] * 0.41), (box["width"] * 0.63, box["height"] * 0.44)
    page.mouse.move(box["x"] + s0[0], box["y"] + s0[1])
    page.mouse.down()
    page.mouse.move(box["x"] + s1[0], box["y"] + s1[1], steps=5)
    page.mouse.up()
    wait_for(lambda: state.get_attribute("data-objects") == str(len(objects) + 1), what="the added line")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    after = _objects(_sent(platform, original))
    added = next(k for k, o in enumerate(after) if k >= len(objects) or o != objects[k])
    assert after[:added] + after[added + 1 :] == objects  # the edit touched nothing else
    tag, _, pts = after[added]
    assert tag == "line"

    def world(sx: float, sy: float) -> tuple[float, float]:
        return ((sx - cam["width"] / 2) / cam["scale"] + cam["cx"], cam["cy"] - (sy - cam["height"] / 2) / cam["scale"])

    tol = 10 + 2 / cam["scale"]  # the grid, and a pixel either way of the pointer
    for (_, p), want in zip(pts, (world(*s0), world(*s1)), strict=True):
        assert abs(float(p["x"]) - want[0]) <= tol and abs(float(p["y"]) - want[1]) <= tol, (p, want)
        assert float(p["x"]) % 10 == 0 and float(p["y"]) % 10 == 0

    # undo, send: the platform has the original objects again, exactly (the round trip through the editor)
    page.get_by_role("button", name="Undo", exact=True).click()
    wait_for(lambda: state.get_attribute("data-objects") == str(len(objects)), what="undo")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    wait_for(lambda: _objects(platform.other.get_map().xml) == objects, what="the original map back")
    page.get_by_role("button", name="Redo", exact=True).click()
    wait_for(lambda: state.get_attribute("data-objects") == str(len(objects) + 1), what="redo")


def test_trim_against_a_parallel_line_says_why_and_changes_nothing(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    objects = _objects(platform.other.get_map().xml)
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: state.get_attribute("data-objects") == str(len(objects)), what="the loaded map")
    page.get_by_role("button", name="Trim", exact=True).click()
    expect_text(page.get_by_role("note", name="Tool tip"), "Trim a line in respect of another line")

    def click(x: float, y: float) -> None:
        page.mouse.click(*aim(page, x, y))

    click(10000, 11200)  # the corridor's north wall (9100,11200)-(18400,11200) ...
    wait_for(
        lambda: '"points":[9100,11200,18400,11200]' in (state.get_attribute("data-selected") or ""),
        what="the first line selected",
    )
    click(12000, 8800)  # ... against its south wall, parallel to it
    expect_text(page.get_by_role("status", name="Messages", exact=True), "the lines are parallel: they never cross")
    assert state.get_attribute("data-objects") == str(len(objects))
    assert state.get_attribute("data-dirty") == "false"
    assert page.get_by_role("button", name="Undo", exact=True).is_disabled()
