"""The map editor's object tools, vertex editing, select all, measuring, Save as, Clear and the close question, and
the roadmap editor's path points (issue 20, guide 5.4 and 5.5), in Debian's chromium against the reference
server. What the editor sent is read back over the platform's OTHER port (CMD_GET_MAP / CMD_GET_ROADMAP) with a
plain client; a saved file is read from the download. Points are placed on the fixture office's wall ends, where
the editor's endpoint snap makes them exact."""

from __future__ import annotations

import functools
import json
import xml.etree.ElementTree as ET
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tests.gui.conftest import REPO, Gateway, Platform, aim, expect_text, settled_view, wait_for
from tests.gui.test_editor import _objects, _open_editor, _sent
from tests.gui.test_editor_documents import tree
from tests.gui.test_editor_motion import _open_roadmap_editor, drag

Obj = tuple[str, dict[str, str], list[tuple[str, dict[str, str]]]]


def messages(page: Any) -> Any:
    return page.get_by_role("status", name="Messages", exact=True)


def obj(tag: str, points: Sequence[float], attrs: dict[str, str] | None = None, r: float | None = None) -> Obj:
    """An object as `_objects` gives it: a circle's first point is its <center>, then its <radius>."""
    child = "center" if tag == "circle" else "point"
    kids = [(child, {"x": f"{points[i]:g}", "y": f"{points[i + 1]:g}"}) for i in range(0, len(points), 2)]
    if r is not None:
        kids.append(("radius", {"r": f"{r:g}"}))
    return (tag, attrs or {}, kids)


def key(o: Obj) -> str:
    return json.dumps(o, sort_keys=True)


def click(page: Any, x: float, y: float, button: str = "left") -> None:
    page.mouse.click(*aim(page, x, y), button=button)


def tool(page: Any, name: str) -> None:
    page.get_by_role("button", name=name, exact=True).click()


def n_is(state: Any, n: int) -> bool:
    return bool(state.get_attribute("data-objects") == str(n))


def _draw_polygons(page: Any) -> None:
    """A workarea (closed by a right-click), a prohibited zone (Enter), a hidden polygon (its first vertex again)."""
    tool(page, "Workarea")
    for p in [(0, 0), (32000, 0), (32000, 11200), (0, 11200)]:
        click(page, *p)
    click(page, 16000, 16000, button="right")  # the new workarea replaces the old one
    tool(page, "Prohibited zone")
    for p in [(9100, 11200), (18400, 11200), (15000, 20000)]:
        click(page, *p)
    page.keyboard.press("Enter")
    tool(page, "Hidden polygon")
    for p in [(0, 8800), (6400, 8800), (9000, 0), (0, 8800)]:
        click(page, *p)


def test_object_tools_and_typed_coordinates_reach_the_platform(page: Any, gateway: Gateway, platform: Platform) -> None:
    original = platform.other.get_map().xml
    objects = _objects(original)
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: n_is(state, len(objects)), what="the loaded map")

    # typed coordinates (mm and degrees): the wall (5600,11200)-(7900,11200) turned north, 2000 mm long
    tool(page, "Edit objects")
    click(page, 6500, 11200)
    wait_for(
        lambda: '"points":[5600,11200,7900,11200]' in (state.get_attribute("data-selected") or ""), what="the wall"
    )
    assert page.get_by_label("Direction (degrees)").input_value() == "0"
    page.get_by_label("Length (mm)").fill("2000")
    page.get_by_label("Direction (degrees)").fill("90")
    tool(page, "Apply coordinates")
    wait_for(lambda: '"points":[5600,11200,5600,13200]' in (state.get_attribute("data-selected") or ""), what="typed")

    # Invert direction of a wall, and Delete a pillar (selected by its rim)
    click(page, 9000, 4000)
    wait_for(lambda: '"points":[9000,0,9000,8800]' in (state.get_attribute("data-selected") or ""), what="the wall")
    tool(page, "Invert direction")
    wait_for(lambda: '"points":[9000,8800,9000,0]' in (state.get_attribute("data-selected") or ""), what="inverted")
    click(page, 20250, 4000)
    wait_for(
        lambda: '"kind":"circle","points":[20000,4000]' in (state.get_attribute("data-selected") or ""), what="pillar"
    )
    tool(page, "Delete")
    wait_for(lambda: n_is(state, len(objects) - 1), what="the pillar deleted")

    tool(page, "Add a reflector")
    drag(page, (23000, 11200), (24200, 11200))
    tool(page, "Add a circle")
    drag(page, (3500, 16000), (7000, 20000))  # radius 5315.07 mm, rounded to the 10 mm grid
    _draw_polygons(page)
    page.get_by_label("Label text").fill("Entrance")
    tool(page, "Add a label")
    click(page, 7000, 20000)
    wait_for(lambda: n_is(state, len(objects) + 4), what="five objects added, the workarea replaced, one deleted")

    # a polygon of two vertices is refused with its reason and changes nothing
    tool(page, "Prohibited zone")
    click(page, 0, 0)
    click(page, 9000, 0)
    tool(page, "Finish polygon")
    expect_text(messages(page), "a polygon needs 3 vertices or more (got 2)")
    assert n_is(state, len(objects) + 4)

    tool(page, "Send to platform")
    # CMD_SET_MAP has no reply: the editor reads GET_MAP after it and says the map is active
    expect_text(
        messages(page), f"Map sent to the platform and active (CMD_GET_MAP returns it): {len(objects) + 4} objects"
    )
    got = _objects(_sent(platform, original))
    removed = [
        obj("workarea", [0, 0, 32000, 0, 32000, 20000, 0, 20000]),
        obj("line", [5600, 11200, 7900, 11200]),
        obj("line", [9000, 0, 9000, 8800]),
        obj("circle", [20000, 4000], r=250),
    ]
    added = [
        obj("line", [5600, 11200, 5600, 13200]),
        obj("line", [9000, 8800, 9000, 0]),
        obj("reflmark", [23000, 11200, 24200, 11200]),
        obj("circle", [3500, 16000], r=5320),
        obj("workarea", [0, 0, 32000, 0, 32000, 11200, 0, 11200]),
        obj("prohibit", [9100, 11200, 18400, 11200, 15000, 20000]),
        obj("hiddenpolygon", [0, 8800, 6400, 8800, 9000, 0]),
        obj("hiddenlabel", [7000, 20000], {"text": "Entrance"}),
    ]
    want = Counter(map(key, objects)) - Counter(map(key, removed)) + Counter(map(key, added))
    assert Counter(map(key, got)) == want
    kept = [o for o in objects if o not in removed]
    assert [o for o in got if o in kept] == kept  # the objects not touched keep their order


def test_line_tools_extend_parallel_and_orthogonal_reach_the_platform(
    page: Any, gateway: Gateway, platform: Platform
) -> None:
    original = platform.other.get_map().xml
    objects = _objects(original)
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: n_is(state, len(objects)), what="the loaded map")
    steps = [
        # (tool, the line clicked, the reference line clicked)
        ("Extend", (4000, 11200), (7000, 15000)),  # corridor wall (0,11200)-(4400,11200) to the wall x = 7000
        (
            "Make orthogonal",
            (5300, 14000),
            (4500, 8800),
        ),  # aux line (1500,14000)-(5500,14000), turned about its west end
        ("Make parallel", (12800, 14500), (15000, 16000)),  # aux line (9500,14500)-(13000,14500) to the wall x = 15000
    ]
    for name, line, ref in steps:
        tool(page, name)
        click(page, *line)
        click(page, *ref)
        expect_text(messages(page), name.lower().removeprefix("make "))  # the command's label
    changes = {
        key(obj("line", [0, 11200, 4400, 11200])): obj("line", [0, 11200, 7000, 11200]),
        key(obj("auxline", [1500, 14000, 5500, 14000])): obj("auxline", [1500, 14000, 1500, 18000]),
        key(obj("auxline", [9500, 14500, 13000, 14500])): obj("auxline", [9500, 14500, 9500, 18000]),
    }
    # undone and redone all three before sending: the platform gets exact coordinates, nothing else changed
    for name in ["Undo"] * 3 + ["Redo"] * 3:
        tool(page, name)
    tool(page, "Send to platform")
    assert _objects(_sent(platform, original)) == [changes.get(key(o), o) for o in objects]


def test_vertices_measuring_select_all_and_clear(page: Any, gateway: Gateway, platform: Platform) -> None:
    original = platform.other.get_map().xml
    objects = _objects(original)
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: n_is(state, len(objects)), what="the loaded map")

    # a vertex of the prohibited zone dragged onto a wall's end
    tool(page, "Edit vertices")
    drag(page, (14500, 5500), (15000, 8800))
    # a vertex added on the zone's south edge and dragged onto another wall's end; one of the hidden polygon's
    # vertices deleted by a right-click
    drag(page, (12000, 1000), (9000, 0))
    click(page, 3000, 8800, button="right")
    zone = [11000, 1000, 9000, 0, 14500, 1000, 15000, 8800, 11000, 5500]
    hidden = [0, 8800, 3000, 11200, 0, 11200]
    edits = {"prohibit": obj("prohibit", zone), "hiddenpolygon": obj("hiddenpolygon", hidden)}
    edited = [edits.get(o[0], o) for o in objects]
    wait_for(lambda: state.get_attribute("data-dirty") == "true", what="the vertex edits")

    # the measuring tool: corner to corner of the office (its ends snap to the wall ends), nothing changes
    tool(page, "Measure")
    drag(page, (0, 0), (32000, 20000))
    expect_text(messages(page), "Distance 37735.9 mm (dx 32000 mm, dy 20000 mm), direction 32°")
    assert json.loads(state.get_attribute("data-measure")) == {
        "distance": 37735.9,
        "dx": 32000,
        "dy": 20000,
        "angle": 32,
    }

    # select all and drag: every object moves by the same grid step
    tool(page, "Select all")
    expect_text(state, f"{len(objects)} objects selected")
    drag(page, (20000, 0), (21000, 500))
    tool(page, "Send to platform")
    moved = _objects(_sent(platform, original))
    (_, _, kids) = moved[0]
    dx, dy = float(kids[0][1]["x"]), float(kids[0][1]["y"])  # the workarea's first point was (0, 0)
    assert abs(dx - 1000) <= 60 and abs(dy - 500) <= 60 and dx % 10 == 0 and dy % 10 == 0, (dx, dy)

    def shifted(o: Obj) -> Obj:
        tag, attrs, ks = o
        return (
            tag,
            attrs,
            [(t, {"x": f"{float(a['x']) + dx:g}", "y": f"{float(a['y']) + dy:g}"} if "x" in a else a) for t, a in ks],
        )

    assert moved == [shifted(o) for o in edited]

    # Ctrl+Z undoes the move: the platform gets the vertex edit alone, exactly
    page.get_by_role("img", name="Map").focus()
    page.keyboard.press("Control+z")
    tool(page, "Send to platform")
    wait_for(lambda: _objects(platform.other.get_map().xml) == edited, what="the move undone on the platform")

    # Clear removes every object in one undoable step
    tool(page, "Clear the map")
    wait_for(lambda: n_is(state, 0), what="the cleared map")
    tool(page, "Undo")
    wait_for(lambda: n_is(state, len(objects)), what="clear undone")


def test_save_as_tooltips_and_the_close_question(
    page: Any, gateway: Gateway, platform: Platform, tmp_path: Path
) -> None:
    objects = _objects(platform.other.get_map().xml)
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: n_is(state, len(objects)), what="the loaded map")
    tip = page.get_by_role("note", name="Tool tip")
    page.get_by_role("button", name="Add a circle", exact=True).hover()
    expect_text(tip, "Add a circle. Left-click to begin and drag to draw a circle.")
    page.get_by_role("button", name="Save as", exact=True).hover()
    expect_text(tip, "Save a map as a new file.")

    # objects on top of each other: a click selects the top one, the next click at the same spot the one beneath
    def kind_is(want: str) -> bool:
        return bool(json.loads(state.get_attribute("data-selected") or "{}").get("kind") == want)

    for want in ("hiddenpolygon", "line", "hiddenpolygon"):  # the lobby's outline lies on the corridor's wall
        click(page, 1000, 11200)
        wait_for(functools.partial(kind_is, want), what=f"the {want} selected")

    # Save as: the file name asked for, the document downloaded under it, equal to the platform's map
    tool(page, "Save as")
    box = page.get_by_role("dialog", name="Save the map as a new file")
    box.get_by_label("File name").fill("lab floor")
    with page.expect_download() as got:
        box.get_by_role("button", name="Save as", exact=True).click()
    assert got.value.suggested_filename == "lab floor.map"
    saved = tmp_path / "saved.map"
    got.value.save_as(saved)
    assert _objects(saved.read_bytes()) == objects
    expect_text(messages(page), "Map saved as lab floor.map")

    # closing with unsaved changes asks; Cancel keeps the editor, "Close without saving" drops the changes
    tool(page, "Clear the map")
    wait_for(lambda: n_is(state, 0), what="the cleared map")
    tool(page, "Close the toolbar")
    ask = page.get_by_role("dialog", name="Unsaved changes")
    expect_text(ask, "neither saved nor sent")
    ask.get_by_role("button", name="Cancel", exact=True).click()
    assert ask.count() == 0
    assert page.get_by_role("toolbar", name="Map editor").is_visible()
    tool(page, "Close the toolbar")
    page.get_by_role("dialog", name="Unsaved changes").get_by_role("button", name="Close without saving").click()
    expect_text(messages(page), "Map editor closed")
    assert not page.get_by_role("toolbar", name="Map editor").is_visible()
    # the platform's map is shown again and its map is untouched
    assert _objects(platform.other.get_map().xml) == objects

    # reopened: an empty new map, and closing a map without changes asks nothing
    page.get_by_role("menuitem", name="Edit", exact=True).click()
    page.get_by_role("menuitem", name="Edit Map", exact=True).click()
    wait_for(lambda: n_is(state, 0), what="a new map after discarding")
    assert state.get_attribute("data-dirty") == "false"
    tool(page, "Close the toolbar")
    assert page.get_by_role("dialog").count() == 0
    assert not page.get_by_role("toolbar", name="Map editor").is_visible()


def test_roadmap_path_points_are_added_and_deleted_on_the_platform(
    page: Any, gateway: Gateway, platform: Platform, tmp_path: Path
) -> None:
    before = platform.other.get_roadmap().xml
    state = _open_roadmap_editor(page, gateway, platform)
    tool(page, "Load from platform")
    expect_text(messages(page), "Roadmap loaded into the editor: 18 stations, 17 edges")
    tool(page, "Edit path points")
    expect_text(page.get_by_role("note", name="Tool tip"), "Click an edge to select it")
    click(page, 3000, 10000)  # the edge Corridor_W -> Corridor_01
    expect_text(messages(page), "Edge Corridor_W -> Corridor_01 selected: 0 path points")
    click(page, 3000, 9400)  # a path point 600 mm south of the corridor's centre line
    expect_text(messages(page), "Path points of edge Corridor_W -> Corridor_01: 1")
    edge = json.loads(state.get_attribute("data-edge"))
    px, py = edge["points"]
    cam = json.loads(page.get_by_role("img", name="Map").get_attribute("data-camera"))
    tol = 10 + 2 / cam["scale"]  # the grid, and a pixel either way of the pointer
    assert abs(px - 3000) <= tol and abs(py - 9400) <= tol and px % 10 == 0 and py % 10 == 0, (px, py)
    click(page, 5000, 11200, button="right")  # the path point of Corridor_01 -> Kitchen, deleted
    expect_text(messages(page), "Path points of edge Corridor_01 -> Kitchen: 0")
    tool(page, "Send to platform")
    expect_text(messages(page), "Roadmap sent to the platform and active (CMD_GET_ROADMAP returns it): 18 stations")

    def sent() -> Any:
        xml = platform.other.get_roadmap().xml
        return xml != before and ET.fromstring(xml)

    root = wait_for(sent, what="the roadmap sent")
    edges = {(e.get("startstation"), e.get("endstation")): e for e in root.findall("edges/edge")}

    def pts(e: ET.Element) -> list[tuple[float, float]]:
        return [(float(p.get("x", "")), float(p.get("y", ""))) for p in e.iter("point")]

    assert pts(edges[("c_west", "c_01")]) == [(px, py)]
    assert pts(edges[("c_01", "r_kitchen")]) == []
    old = ET.fromstring(before)
    others = [(e.get("startstation"), e.get("endstation"), pts(e)) for e in old.findall("edges/edge")]
    assert [o for o in others if o[:2] not in {("c_west", "c_01"), ("c_01", "r_kitchen")}] == [
        (e.get("startstation"), e.get("endstation"), pts(e))
        for e in root.findall("edges/edge")
        if (e.get("startstation"), e.get("endstation")) not in {("c_west", "c_01"), ("c_01", "r_kitchen")}
    ]
    _roadmap_files_and_the_close_question(page, state, root, tmp_path)


def _roadmap_files_and_the_close_question(page: Any, state: Any, root: ET.Element, tmp_path: Path) -> None:
    # Save as: the roadmap the platform got, downloaded under the name asked for
    tool(page, "Save as")
    box = page.get_by_role("dialog", name="Save the roadmap as a new file")
    box.get_by_label("File name").fill("corridor")
    with page.expect_download() as got:
        box.get_by_role("button", name="Save as", exact=True).click()
    assert got.value.suggested_filename == "corridor.rm"
    saved = tmp_path / "corridor.rm"
    got.value.save_as(saved)
    assert tree(ET.fromstring(saved.read_bytes())) == tree(root)
    # Open a roadmap file: the fixture is read; a map file is refused and the editor keeps the fixture
    opener = page.get_by_label("Open a roadmap file")
    opener.set_input_files(str(REPO / "fixtures" / "roadmaps" / "office.rm"))
    expect_text(messages(page), "Roadmap file office.rm opened in the editor: 18 stations, 17 edges")
    opener.set_input_files(str(REPO / "fixtures" / "maps" / "office.map"))
    expect_text(messages(page), "office.map not opened: expected a <roadmap> document, got <map>")
    assert state.get_attribute("data-stations") == "18"

    # closing with changes asks; Save downloads the roadmap and closes; reopened, the editor has it still
    tool(page, "Clear roadmap")
    wait_for(lambda: state.get_attribute("data-stations") == "0", what="the cleared roadmap")
    tool(page, "Close the toolbar")
    with page.expect_download() as got:
        page.get_by_role("dialog", name="Unsaved changes").get_by_role("button", name="Save", exact=True).click()
    got.value.save_as(tmp_path / "cleared.rm")
    assert not ET.fromstring((tmp_path / "cleared.rm").read_bytes()).findall("stations/station")
    expect_text(messages(page), "Roadmap editor closed")
    assert not page.get_by_role("toolbar", name="Roadmap editor").is_visible()
    page.get_by_role("menuitem", name="Edit", exact=True).click()
    page.get_by_role("menuitem", name="Edit Roadmap", exact=True).click()
    assert state.get_attribute("data-dirty") == "false" and state.get_attribute("data-stations") == "0"


def _layers(xml: str | bytes) -> dict[str, list[Any]]:
    """The map's layers by index: each one's attributes and objects (tag, attributes, children), in order."""
    root = ET.fromstring(xml)
    return {la.get("index", ""): [dict(la.attrib), [tree(o) for o in la]] for la in root.findall("layer")}


def test_new_objects_go_into_the_chosen_layer(page: Any, gateway: Gateway, platform: Platform) -> None:
    original = platform.other.get_map().xml
    before = _layers(original)
    assert list(before) == ["0", "1", "2"]  # the fixture office
    state = _open_editor(page, gateway, platform)
    wait_for(lambda: n_is(state, len(_objects(original))), what="the loaded map")
    layer = page.get_by_role("combobox", name="Layer for new objects", exact=True)
    # the document's layers and the next free index; the first layer of the document chosen
    assert layer.locator("option").all_inner_texts() == ["0", "1", "2", "3 (new layer)"]
    assert layer.input_value() == "0"

    # from pillar to pillar (their centers, where the endpoint snap makes the lines exact)
    tool(page, "Add a line")
    layer.select_option("2")
    drag(page, (11000, 16500), (19000, 16000))
    layer.select_option("3")
    drag(page, (19000, 16000), (28000, 16500))
    wait_for(lambda: n_is(state, len(_objects(original)) + 2), what="two lines added")
    wait_for(lambda: layer.locator("option").all_inner_texts()[-1] == "4 (new layer)", what="layer 3 started")
    # a circle into layer 1, the pillars' layer
    tool(page, "Add a circle")
    layer.select_option("1")
    drag(page, (15000, 5000), (15500, 5000))
    wait_for(lambda: n_is(state, len(_objects(original)) + 3), what="the circle added")
    tol = 10 + 2 / settled_view(page)[0]["scale"]  # the grid, and a pixel either way of the pointer

    tool(page, "Send to platform")
    sent = _sent(platform, original)
    after = _layers(sent)
    assert ET.fromstring(sent).attrib == ET.fromstring(original).attrib
    assert list(after) == ["0", "1", "2", "3"]
    assert after["0"] == before["0"]  # nothing else changed
    assert after["1"][0] == before["1"][0] and after["1"][1][:-1] == before["1"][1]
    tag, _, (center, radius) = after["1"][1][-1]
    assert (tag, center[0], radius[0]) == ("circle", "center", "radius"), after["1"][1][-1]
    assert abs(float(center[1]["x"]) - 15000) <= tol and abs(float(center[1]["y"]) - 5000) <= tol, center
    assert abs(float(radius[1]["r"]) - 500) <= tol, radius
    assert after["2"][0] == before["2"][0] and after["2"][1][:-1] == before["2"][1]
    line = ("line", {}, [("point", {"x": "11000", "y": "16500"}, []), ("point", {"x": "19000", "y": "16000"}, [])])
    line3 = ("line", {}, [("point", {"x": "19000", "y": "16000"}, []), ("point", {"x": "28000", "y": "16500"}, [])])
    assert after["2"][1][-1] == line
    assert after["3"] == [{"index": "3"}, [line3]]
