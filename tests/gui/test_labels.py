"""Labels without overlap on the map view (issue 35), in Debian's chromium against the reference server and its
office map: the station names and the map's labels (hiddenlabel: room names) are placed so that no two overlap -
a lower-priority one (a room under a station) is moved to another free place around its point, or hidden at that
zoom. Checked from the boxes of the texts the static layer drew (``window.pltf.map.labels()``, canvas px)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tests.gui.conftest import Gateway, Platform, open_gui, settled_view, wait_for

Box = dict[str, Any]


def drawn_labels(page: Any) -> list[Box]:
    """The texts of the current static layer, once the view has settled and the layer has drawn the roadmap."""
    canvas = page.get_by_role("img", name="Map")
    wait_for(lambda: int(canvas.get_attribute("data-drawn-station") or 0) > 0, what="the roadmap drawn")
    settled_view(page)
    boxes: list[Box] = page.evaluate("() => window.pltf.map.labels()")
    return boxes


def meet(a: Box, b: Box) -> bool:
    """Do two boxes overlap (touching edges do not)?"""
    apart_x = a["x"] >= b["x"] + b["w"] or b["x"] >= a["x"] + a["w"]
    return not apart_x and a["y"] < b["y"] + b["h"] and b["y"] < a["y"] + a["h"]


def overlapping(boxes: list[Box]) -> list[tuple[str, str]]:
    """The pairs of texts whose boxes overlap."""
    return [(a["text"], b["text"]) for i, a in enumerate(boxes) for b in boxes[i + 1 :] if meet(a, b)]


def in_view(page: Any, boxes: list[Box]) -> list[Box]:
    """The texts that lie at least partly on the canvas (the layer also draws a margin around it)."""
    box = page.get_by_role("img", name="Map").bounding_box()
    canvas = {"x": 0, "y": 0, "w": box["width"], "h": box["height"]}
    return [b for b in boxes if meet(b, canvas)]


def test_no_two_station_names_overlap_at_the_default_zoom_nor_any_text_zoomed_out(
    page: Any, gateway: Gateway, platform: Platform, artifacts: Path
) -> None:
    open_gui(page, gateway, platform.target)
    labels = drawn_labels(page)
    page.get_by_role("img", name="Map").screenshot(path=str(artifacts / "labels-default.png"))
    names = [b for b in in_view(page, labels) if b["kind"] == "station"]
    # the office roadmap's crowded corridor: both names are drawn, apart
    assert {"Corridor_02", "Corridor_03", "Corridor_W"} <= {b["text"] for b in names}, names
    assert overlapping(names) == []
    for _ in range(2):
        page.get_by_role("button", name="Zoom out", exact=True).click()
    labels = drawn_labels(page)
    page.get_by_role("img", name="Map").screenshot(path=str(artifacts / "labels-zoomed-out.png"))
    shown = in_view(page, labels)
    assert len(shown) > 0
    assert overlapping(labels) == []
    canvas = page.get_by_role("img", name="Map")
    assert int(canvas.get_attribute("data-hidden-labels") or 0) > 0  # zoomed out, some had to give way
