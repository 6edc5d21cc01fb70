"""The editors' documents (issue 20) in Debian's chromium against the reference server: what reaches the platform
is checked over its OTHER port. Round trips keep every object and attribute; a document invalid against the
project's XSD (spec/schemas) is not sent, and the editor selects the object at fault."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

from tests.gui.conftest import REPO, Gateway, Platform, aim, expect_text, open_gui, settled_view, wait_for
from tests.gui.fakes import HeldReplies
from tests.gui.test_editor import _objects, _open_editor, _sent
from tests.gui.test_editor_motion import drag, running_automatic

FIXTURE_MAP = REPO / "fixtures" / "maps" / "office.map"
FIXTURE_ROADMAP = REPO / "fixtures" / "roadmaps" / "office.rm"
SMALL_MAP = '<map Version="1.0"><layer index="0"><line><point x="0" y="0"/><point x="100" y="0"/></line></layer></map>'
SMALL_ROADMAP = '<roadmap Version="1.0"><stations/><edges/></roadmap>'


def tree(el: ET.Element) -> tuple[str, dict[str, str], list[Any]]:
    """An element as tag, attributes and children, recursively (text and comments left out)."""
    return (el.tag, dict(el.attrib), [tree(c) for c in el])


def messages(page: Any) -> Any:
    return page.get_by_role("status", name="Messages", exact=True)


def test_the_fixture_map_loaded_and_sent_back_reaches_the_platform_unchanged(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    fixture = _objects(FIXTURE_MAP.read_bytes())
    assert _objects(platform.other.get_map().xml) == fixture  # the server booted on the fixture office
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: state.get_attribute("data-objects") == str(len(fixture)), what="the loaded map")
    platform.other.set_map("small", SMALL_MAP)  # so the editor's send is seen
    wait_for(lambda: len(_objects(platform.other.get_map().xml)) == 1, what="the small map")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    expect_text(messages(page), "Map sent to the platform")
    wait_for(lambda: _objects(platform.other.get_map().xml) == fixture, what="the fixture's objects, every attribute")


def test_a_map_file_invalid_against_the_xsd_is_not_sent_and_its_object_is_selected(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    before = platform.other.get_map().xml
    state = _open_editor(page, gateway, platform)
    page.get_by_label("Open a map file").set_input_files(str(REPO / "fixtures" / "invalid" / "missing_point.map"))
    expect_text(messages(page), "missing_point.map opened in the editor: 2 objects")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    expect_text(messages(page), "Not sent: the document is invalid")
    expect_text(messages(page), "Element 'line': Missing child element(s)")
    # the object at fault is selected on the view: the line with its single point
    assert '"kind":"line","points":[0,0]' in (state.get_attribute("data-selected") or "")
    assert state.get_attribute("data-dirty") == "false"
    # the platform's active map is untouched: a valid send after it shows the GUI's link still in order
    assert platform.other.get_map().xml == before


def test_a_file_of_the_wrong_kind_is_refused_and_the_editor_keeps_its_map(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    n = len(_objects(platform.other.get_map().xml))
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: state.get_attribute("data-objects") == str(n), what="the loaded map")
    page.get_by_label("Open a map file").set_input_files(str(FIXTURE_ROADMAP))
    expect_text(messages(page), "office.rm not opened: expected a <map> document, got <roadmap>")
    assert state.get_attribute("data-objects") == str(n)


def test_the_fixture_roadmap_loaded_and_sent_back_reaches_the_platform_unchanged(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    fixture = tree(ET.fromstring(FIXTURE_ROADMAP.read_bytes()))
    assert tree(ET.fromstring(platform.other.get_roadmap().xml)) == fixture
    open_gui(page, gateway, platform.target)
    page.get_by_role("menuitem", name="Edit", exact=True).click()
    page.get_by_role("menuitem", name="Edit Roadmap", exact=True).click()
    page.get_by_role("button", name="Load from platform", exact=True).click()
    expect_text(messages(page), "Roadmap loaded into the editor: 18 stations, 17 edges")
    platform.other.set_roadmap("empty", SMALL_ROADMAP)
    wait_for(lambda: not ET.fromstring(platform.other.get_roadmap().xml).findall("stations/station"), what="empty")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    expect_text(messages(page), "Roadmap sent to the platform")
    wait_for(lambda: tree(ET.fromstring(platform.other.get_roadmap().xml)) == fixture, what="the fixture roadmap")


def test_the_platform_map_answered_after_the_roadmap_editor_opened_is_drawn_under_the_editor_roadmap(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    """The roadmap editor edits the roadmap over the platform's map (guide 5.5): a GET_MAP answered late (a busy
    platform, a reconnect) still brings the map; a late GET_ROADMAP does not replace the editor's roadmap (CI,
    stop 28: the map never appeared, and no station could be placed near its walls)."""
    with HeldReplies(platform.ports[0]) as relay:
        open_gui(page, gateway, relay.target)
        page.get_by_role("menuitem", name="Edit", exact=True).click()
        page.get_by_role("menuitem", name="Edit Roadmap", exact=True).click()
        state = page.locator("output.rm-state")
        wait_for(lambda: state.get_attribute("data-stations") == "0", what="the editor's new roadmap")
        canvas = page.get_by_role("img", name="Map")
        assert canvas.get_attribute("data-drawn-line") in (None, "0")  # no reply has come yet
        relay.release()
        settled_view(page)  # lines drawn: the platform's map
        lines = sum(tag == "line" for tag, _, _ in _objects(platform.other.get_map().xml))
        assert lines > 0 and canvas.get_attribute("data-drawn-line") == str(lines)
        assert canvas.get_attribute("data-drawn-station") == "0"  # the editor's roadmap, not the platform's 18


def _segments(xml: str | bytes, kinds: tuple[str, ...]) -> list[tuple[float, float, float, float]]:
    out = []
    for tag, _, pts in _objects(xml):
        if tag in kinds and len(pts) == 2:
            (_, a), (_, b) = pts
            out.append((float(a["x"]), float(a["y"]), float(b["x"]), float(b["y"])))
    return out


def _distance(px: float, py: float, s: tuple[float, float, float, float]) -> float:
    ax, ay, bx, by = s
    dx, dy = bx - ax, by - ay
    u = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)))
    return float(((px - ax - u * dx) ** 2 + (py - ay - u * dy) ** 2) ** 0.5)


Segment = tuple[float, float, float, float]
START = (2000, 10000)  # where the platform starts in fixtures/maps/office.map (the reference server's default)


def _nearest(walls: list[Segment], s: Segment) -> Segment:
    return min(walls, key=lambda w: _distance(s[0], s[1], w) + _distance(s[2], s[3], w))


def _turn(s: Segment, wall: Segment) -> float:
    """The angle between two segments' directions, 0-90 degrees."""
    a = math.atan2(s[3] - s[1], s[2] - s[0]) - math.atan2(wall[3] - wall[1], wall[2] - wall[0])
    return math.degrees(abs(math.atan(math.tan(a))))


def test_lines_converted_from_a_scan_of_the_office_lie_within_30_mm_of_its_walls(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    original = platform.other.get_map().xml
    walls = _segments(FIXTURE_MAP.read_bytes(), ("line", "auxline"))
    n = len(_objects(original))
    running_automatic(platform)  # the laser scans while the platform is up (start pose (2000, 10000, 0))
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: state.get_attribute("data-objects") == str(n), what="the loaded map")
    page.get_by_role("button", name="Convert lines from scan", exact=True).click()
    expect_text(messages(page), "lines converted from the scan")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    xml = _sent(platform, original)
    mapped, aux = _segments(xml, ("linemapped",)), _segments(xml, ("auxlinemapped",))
    sent = mapped + aux
    assert len(sent) >= 2, sent  # at least the corridor's two walls
    assert max(math.dist(s[:2], s[2:]) for s in sent) >= 3000  # long stretches of wall, not only crumbs

    # the reference server's laser has a noise of 10 mm + 0.1 % of the range (reference_server/world/sensors.py):
    # at 30 m (the corridor's far end) a fitted line cannot keep 30 mm; judged are the lines within 12 m
    def near(lines: list[Segment]) -> list[Segment]:
        return [s for s in lines if max(math.dist(s[:2], START), math.dist(s[2:], START)) <= 12000]

    assert len(near(sent)) >= 2, sent
    for s in near(mapped):  # a mapped line (MinLineLenMap and longer): both ends on its wall
        wall = _nearest(walls, s)
        off = max(_distance(s[0], s[1], wall), _distance(s[2], s[3], wall))
        assert off <= 30, f"converted line {s} lies {off:.0f} mm off the nearest wall {wall}"
    # an auxiliary line is short (MinLineLenAux to MinLineLenMap): a few beams, whose noise can turn it about its
    # middle, the shorter the more (clean clones' make test: 365 mm with ends 31 mm either side of x = 7000, 10
    # degrees; 228 mm with ends 20 and 31 mm off, 13 degrees); its middle lies on the wall and it runs along it:
    # neither end further off than the noise takes it
    for s in near(aux):
        wall = _nearest(walls, s)
        mid = _distance((s[0] + s[2]) / 2, (s[1] + s[3]) / 2, wall)
        assert mid <= 30, f"auxiliary line {s}: its middle lies {mid:.0f} mm off the nearest wall {wall}"
        off = max(_distance(s[0], s[1], wall), _distance(s[2], s[3], wall))
        assert off <= 45, (
            f"auxiliary line {s} is turned {_turn(s, wall):.0f} degrees from its wall {wall}: an end {off:.0f} mm off"
        )


def test_undo_and_redo_of_a_drag_restore_exact_coordinates_on_the_platform(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    original = platform.other.get_map().xml
    objects = _objects(original)
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: state.get_attribute("data-objects") == str(len(objects)), what="the loaded map")
    wall = [9100, 11200, 18400, 11200]  # the corridor's north wall between the meeting room and office N1

    def selected() -> list[float]:
        points: list[float] = json.loads(state.get_attribute("data-selected") or "{}").get("points", [])
        return points

    page.mouse.click(*aim(page, 12000, 11200))
    wait_for(lambda: selected() == wall, what="the wall selected")
    drag(page, (12000, 11200), (12700, 12100))
    wait_for(lambda: selected() != wall, what="the wall moved")
    moved = selected()
    dx, dy = moved[0] - wall[0], moved[1] - wall[1]
    assert moved == [wall[0] + dx, wall[1] + dy, wall[2] + dx, wall[3] + dy] and dx % 10 == 0 and dy % 10 == 0
    assert abs(dx - 700) <= 100 and abs(dy - 900) <= 100, (dx, dy)
    page.get_by_role("button", name="Undo", exact=True).click()
    wait_for(lambda: selected() == wall, what="undo: the wall where it was, exactly")
    page.get_by_role("button", name="Redo", exact=True).click()
    wait_for(lambda: selected() == moved, what="redo: the wall moved again, exactly")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    after = _objects(_sent(platform, original))
    k = next(i for i, o in enumerate(objects) if o[0] == "line" and o[2][0][1] == {"x": "9100", "y": "11200"})
    assert [(float(p["x"]), float(p["y"])) for _, p in after[k][2]] == [(moved[0], moved[1]), (moved[2], moved[3])]
    assert after[:k] + after[k + 1 :] == objects[:k] + objects[k + 1 :]  # nothing else changed
    page.get_by_role("button", name="Undo", exact=True).click()
    wait_for(lambda: selected() == wall, what="undo again")
    page.get_by_role("button", name="Send to platform", exact=True).click()
    wait_for(lambda: _objects(platform.other.get_map().xml) == objects, what="the original map, exactly")


def test_save_downloads_the_platform_map_and_roadmap_unchanged(page: Any, gateway: Gateway, platform: Platform) -> None:
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: state.get_attribute("data-objects") == str(len(_objects(FIXTURE_MAP.read_bytes()))), what="map")
    with page.expect_download() as got:
        page.get_by_role("button", name="Save", exact=True).click()
    saved = Path(got.value.path()).read_bytes()
    assert got.value.suggested_filename.endswith(".map")
    assert tree(ET.fromstring(saved)) == tree(ET.fromstring(FIXTURE_MAP.read_bytes()))
    page.get_by_role("menuitem", name="Edit", exact=True).click()
    page.get_by_role("menuitem", name="Edit Roadmap", exact=True).click()
    page.get_by_role("button", name="Load from platform", exact=True).click()
    expect_text(messages(page), "Roadmap loaded into the editor: 18 stations, 17 edges")
    with page.expect_download() as got:
        page.get_by_role("button", name="Save", exact=True).click()
    assert got.value.suggested_filename.endswith(".rm")
    assert tree(ET.fromstring(Path(got.value.path()).read_bytes())) == tree(ET.fromstring(FIXTURE_ROADMAP.read_bytes()))
