"""The layout on a laptop and on tablets (issue 35), in Debian's chromium against the reference server: at 1280x800,
1024x768 and 768x1024 (portrait, touch) nothing is cut off at the sides, the page has no horizontal scrollbar, the
map keeps a usable share of the window, and every panel can be reached: the dock's tabs and their panes, the
operation toolbar, the menu bar and the status bar lie inside the window, each pane opens where it can be seen."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.gui.conftest import Gateway, Platform, checked_page, open_gui, settled_view

# name -> viewport, touch, the least share of the window the map must keep
SCREENS = {
    "laptop 1280x800": ({"width": 1280, "height": 800}, False, 0.40),
    "tablet 1024x768": ({"width": 1024, "height": 768}, True, 0.35),
    "tablet portrait 768x1024": ({"width": 768, "height": 1024}, True, 0.30),
}

# what is outside the window's width, and whether the page scrolls sideways
OVERFLOW_JS = """() => {
  const w = document.documentElement.clientWidth;
  const out = [];
  for (const el of document.querySelectorAll('button, select, input, [role=tab], [role=toolbar], canvas, output')) {
    const r = el.getBoundingClientRect();
    if (r.width === 0 || r.height === 0 || el.closest('[hidden]')) continue;
    const name = el.getAttribute('aria-label') ?? el.textContent;
    if (r.left < -0.5 || r.right > w + 0.5) out.push(`${name} ${Math.round(r.left)}..${Math.round(r.right)}`);
  }
  return { scrollWidth: document.documentElement.scrollWidth, clientWidth: w, outside: out };
}"""

# the visible buttons less than 40 px tall (or wide: an icon button)
SMALL_TARGETS_JS = """() => [...document.querySelectorAll('button, select')]
  .filter((el) => !el.closest('[hidden]'))
  .map((el) => [el, el.getBoundingClientRect()])
  .filter(([el, r]) => r.width > 0 && (r.height < 39.5 || r.width < 39.5))
  .map(([el, r]) => `${el.getAttribute('aria-label') ?? el.textContent} ${Math.round(r.width)}x${Math.round(r.height)}`)
"""


@pytest.fixture(params=list(SCREENS))
def screen(request: pytest.FixtureRequest, browser: Any) -> Any:
    viewport, touch, share = SCREENS[request.param]
    with checked_page(browser, viewport=viewport, has_touch=touch, is_mobile=False) as pg:
        yield request.param, pg, viewport, touch, share


def inside(box: dict[str, float] | None, viewport: dict[str, int]) -> bool:
    return (
        box is not None
        and box["x"] >= -0.5
        and box["y"] >= -0.5
        and box["x"] + box["width"] <= viewport["width"] + 0.5
        and box["y"] + box["height"] <= viewport["height"] + 0.5
    )


def test_the_layout_fits_the_window_and_keeps_the_map_usable(
    screen: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    name, page, viewport, touch, share = screen
    open_gui(page, gateway, platform.target)
    settled_view(page)
    slug = name.split()[-1]
    page.screenshot(path=str(artifacts / f"layout-{slug}.png"))
    # no horizontal scrollbar, nothing cut off at the sides
    over = page.evaluate(OVERFLOW_JS)
    assert over["scrollWidth"] <= over["clientWidth"], over
    assert over["outside"] == [], over["outside"]
    # the map: inside the window, at least `share` of it
    canvas = page.get_by_role("img", name="Map")
    box = canvas.bounding_box()
    assert inside(box, viewport), (box, viewport)
    area = box["width"] * box["height"] / (viewport["width"] * viewport["height"])
    assert area >= share, f"the map has {area:.0%} of the window, less than {share:.0%}"
    # the bars: the menu bar, the operation toolbar and the status bar in sight
    for locator in (
        page.get_by_role("menuitem", name="Socket", exact=True),
        page.get_by_role("toolbar", name="Operation", exact=True),
        page.get_by_role("status", name="Connection"),
    ):
        assert inside(locator.bounding_box(), viewport), locator
    # on a touch screen every button is a target of at least 40 px
    if touch:
        small = page.evaluate(SMALL_TARGETS_JS)
        assert small == [], small
    # every dock window: its tab can be reached, and its pane opens where it can be seen
    tabs = page.get_by_role("tablist", name="Windows").get_by_role("tab")
    for i in range(tabs.count()):
        tab = tabs.nth(i)
        tab.scroll_into_view_if_needed()
        assert inside(tab.bounding_box(), viewport), tab.text_content()
        tab.click()
        pane = page.get_by_role("tabpanel", name=tab.text_content() or "", exact=True)
        pane.scroll_into_view_if_needed()
        pbox = pane.bounding_box()
        assert pbox is not None and pbox["height"] >= 80, (tab.text_content(), pbox)
        assert pbox["x"] >= -0.5 and pbox["x"] + pbox["width"] <= viewport["width"] + 0.5, (tab.text_content(), pbox)
    page.screenshot(path=str(artifacts / f"layout-{slug}-last-pane.png"))
    over = page.evaluate(OVERFLOW_JS)
    assert over["scrollWidth"] <= over["clientWidth"], over
