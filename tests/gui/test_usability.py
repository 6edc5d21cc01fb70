"""The GUI as a person meets it (issue 35, part 1), in Debian's chromium: every panel, both editors and the
dialogs are walked; every input, select and textarea shown has an accessible name AND a caption the user sees on
screen; every toolbar button has a tooltip (a non-empty title); Undo and Redo each say which action they took back
or did again, in English and in German. No platform is needed: the panels and editors are walked offline."""

from __future__ import annotations

import json
from typing import Any

import pytest

from tests.gui.conftest import Gateway, Platform, expect_text, open_gui, wait_for
from tests.gui.test_app import button, readout

# The panels of the dock, by the menu and item that open them (English labels).
PANELS = [
    ("View", "Hardware Monitor"),
    ("View", "View Options"),
    ("View", "Plots"),
    ("View", "Log"),
    ("View", "Wire Inspector"),
    ("Parameter", "Platform parameters"),
    ("Edit", "Edit Map"),
    ("Edit", "Edit Roadmap"),
]

# For every form control shown: its accessible name (aria-label, else the text of its <label>) and its caption, the
# text (or, for an icon, the tooltip) of the <label> around it or pointing at it, or of the element named by
# aria-labelledby, when that caption has a box on screen. A control is "shown" when it has a box, or, a file input
# drawn as its icon label, when that label has one.
WALK = """
() => {
  const shown = (el) => {
    const r = el.getBoundingClientRect();
    return r.width > 0 && r.height > 0 && getComputedStyle(el).visibility !== "hidden";
  };
  const missing = [];
  let seen = 0;
  for (const el of document.querySelectorAll("input, select, textarea")) {
    const wrap = el.closest("label");
    if (!shown(el) && !(el.type === "file" && wrap && shown(wrap))) continue;
    seen++;
    const lab = wrap || (el.id ? document.querySelector(`label[for="${el.id}"]`) : null);
    const name = (el.getAttribute("aria-label") || (lab ? lab.innerText : "") || "").trim();
    let caption = "";
    if (lab && shown(lab)) caption = lab.innerText.trim() || lab.title.trim();
    const by = el.getAttribute("aria-labelledby");
    const other = by ? document.getElementById(by) : null;
    if (!caption && other && shown(other)) caption = other.innerText.trim();
    if (!name || !caption) missing.push(`${el.tagName.toLowerCase()}[${el.type}] name=${JSON.stringify(name)} `
      + `caption=${JSON.stringify(caption)} in ${el.parentElement.className || el.parentElement.tagName}`);
  }
  const untitled = [];
  let buttons = 0;
  for (const b of document.querySelectorAll("[role=toolbar] button, [role=toolbar] label.icon-button")) {
    if (!shown(b)) continue;
    buttons++;
    if (!b.title.trim()) untitled.push(b.getAttribute("aria-label") || b.innerText);
  }
  return { seen, missing, buttons, untitled };
}
"""


def _open(page: Any, menu: str, item: str) -> None:
    page.get_by_role("menuitem", name=menu, exact=True).click()
    page.get_by_role("menuitem", name=item, exact=True).click()


def _walk(page: Any, where: str, found: dict[str, list[str]]) -> tuple[int, int]:
    got = page.evaluate(WALK)
    found["missing"] += [f"{where}: {m}" for m in got["missing"]]
    found["untitled"] += [f"{where}: {u}" for u in got["untitled"]]
    return int(got["seen"]), int(got["buttons"])


def test_every_input_has_a_name_and_a_visible_caption_and_every_toolbar_button_a_tooltip(
    page: Any, gateway: Gateway
) -> None:
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
    found: dict[str, list[str]] = {"missing": [], "untitled": []}
    inputs, buttons = _walk(page, "main window", found)
    for menu, item in PANELS:
        _open(page, menu, item)
        seen = _walk(page, item, found)
        inputs, buttons = inputs + seen[0], buttons + seen[1]
    # every tab of the hardware monitor (guide 5.8)
    _open(page, "View", "Hardware Monitor")
    tabs = page.get_by_role("tablist", name="Hardware Monitor").get_by_role("tab")
    assert tabs.count() >= 8  # Motor, IOBoard, RelayBoard, USBoard, Radar, CAN, the TCP tabs
    for k in range(tabs.count()):
        tabs.nth(k).click()
        inputs += _walk(page, f"Hardware Monitor tab {k}", found)[0]
    # the dialogs: Open Socket At, the editors' Save as
    _open(page, "Socket", "Open Socket At")
    dialog = page.get_by_role("dialog")
    dialog.wait_for()
    inputs += _walk(page, "Open Socket At", found)[0]
    dialog.get_by_role("button", name="Cancel", exact=True).click()
    _open(page, "Edit", "Edit Map")
    page.get_by_role("toolbar", name="Map editor", exact=True).get_by_role("button", name="Save as").click()
    page.get_by_role("dialog").wait_for()
    inputs += _walk(page, "Save as", found)[0]
    page.get_by_role("dialog").get_by_role("button", name="Cancel", exact=True).click()
    assert inputs >= 10 and buttons >= 30, (inputs, buttons)  # the walk saw the GUI, not an empty page
    assert found == {"missing": [], "untitled": []}


def test_the_motion_modes_controls_have_names_and_captions(page: Any, gateway: Gateway, platform: Platform) -> None:
    """The motion panel shows each mode's controls only in that mode (guide 5.6): walked in each, connected."""
    open_gui(page, gateway, platform.target)
    button(page, "Init").click()
    expect_text(_messages(page), "Init: CMD_CONNECT_TO_PLTF, CMD_INIT_PLTF sent")  # what the button sent
    expect_text(readout(page, "System state"), "Ready")
    found: dict[str, list[str]] = {"missing": [], "untitled": []}
    inputs = 0
    for mode in ["Velocity", "Automatic", "Post-process replay"]:
        page.get_by_role("combobox", name="Motion mode").select_option(label=mode)
        expect_text(readout(page, "Motion mode"), mode)
        inputs += _walk(page, mode, found)[0]
    assert inputs >= 3 * 1 + 2 + 7, inputs  # the mode select each time; 2 velocities; station and 6 coordinates
    assert found == {"missing": [], "untitled": []}


def test_each_editor_s_toolbar_says_whose_it_is_and_its_buttons_are_icons(page: Any, gateway: Gateway) -> None:
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
    for item, name in [("Edit Map", "Map editor"), ("Edit Roadmap", "Roadmap editor")]:
        _open(page, "Edit", item)
        bar = page.get_by_role("toolbar", name=name, exact=True)
        heading = page.get_by_role("heading", name=name, exact=True)
        assert heading.is_visible()
        hb, tb = heading.bounding_box(), bar.bounding_box()
        assert hb is not None and tb is not None and hb["y"] + hb["height"] <= tb["y"] + 1  # the caption above it
        undo = bar.get_by_role("button", name="Undo", exact=True)
        assert undo.locator("svg").count() == 1 and undo.inner_text().strip() == ""  # an icon, named "Undo"
        assert undo.get_attribute("title") == "Undo (Ctrl+Z)"


def _messages(page: Any, name: str = "Messages") -> Any:
    return page.get_by_role("status", name=name, exact=True)


def _drag_on_map(page: Any, name: str, a: tuple[float, float], b: tuple[float, float]) -> None:
    box = page.get_by_role("img", name=name, exact=True).bounding_box()
    page.mouse.move(box["x"] + box["width"] * a[0], box["y"] + box["height"] * a[1])
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] * b[0], box["y"] + box["height"] * b[1], steps=5)
    page.mouse.up()


# What a user reads after an edit, Undo and Redo, in each language: the words of the menu, the toolbar's buttons
# and the messages line.
WORDS = {
    "en": {
        "edit": "Edit",
        "map": ("Edit Map", "Map editor", "New map", "Add a line", "Undo", "Redo"),
        "roadmap": ("Edit Roadmap", "Roadmap editor", "New roadmap", "Add a station", "Undo", "Redo"),
        "messages": "Messages",
        "canvas": "Map",
        "line": ("Done: add a line", "Undone: add a line", "Redone: add a line"),
        "station": ("Station Station_1 added", "Undone: add station Station_1", "Redone: add station Station_1"),
    },
    "de": {
        "edit": "Bearbeiten",
        "map": ("Karte bearbeiten", "Karteneditor", "Neue Karte", "Linie hinzufügen", "Rückgängig", "Wiederholen"),
        "roadmap": (
            "Roadmap bearbeiten",
            "Roadmap-Editor",
            "Neue Roadmap",
            "Station hinzufügen",
            "Rückgängig",
            "Wiederholen",
        ),
        "messages": "Meldungen",
        "canvas": "Karte",
        "line": (
            "Ausgeführt: Linie hinzufügen",
            "Rückgängig gemacht: Linie hinzufügen",
            "Wiederholt: Linie hinzufügen",
        ),
        "station": (
            "Station Station_1 hinzugefügt",
            "Rückgängig gemacht: Station Station_1 hinzufügen",
            "Wiederholt: Station Station_1 hinzufügen",
        ),
    },
}


@pytest.mark.parametrize("lang", list(WORDS))
def test_undo_and_redo_say_which_action_they_took_back_or_did_again(page: Any, gateway: Gateway, lang: str) -> None:
    w: dict[str, Any] = WORDS[lang]
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
    page.evaluate(f"localStorage.setItem('pltf.lang', '{lang}')")
    page.reload()
    messages = _messages(page, w["messages"])
    for doc, kind in [("map", "line"), ("roadmap", "station")]:
        item, toolbar, new, tool, undo, redo = w[doc]
        page.get_by_role("menuitem", name=w["edit"], exact=True).click()
        page.get_by_role("menuitem", name=item, exact=True).click()
        bar = page.get_by_role("toolbar", name=toolbar, exact=True)
        bar.get_by_role("button", name=new, exact=True).click()
        bar.get_by_role("button", name=tool, exact=True).click()
        if kind == "line":
            _drag_on_map(page, w["canvas"], (0.35, 0.4), (0.6, 0.45))
        else:
            page.get_by_role("img", name=w["canvas"], exact=True).click()
        done, undone, redone = w[kind]
        expect_text(messages, done)
        bar.get_by_role("button", name=undo, exact=True).click()
        expect_text(messages, undone)
        bar.get_by_role("button", name=redo, exact=True).click()
        expect_text(messages, redone)
        # the same from the keyboard, in both editors (ui/icons.ts SHORTCUTS)
        page.get_by_role("img", name=w["canvas"], exact=True).focus()
        page.keyboard.press("Control+z")
        expect_text(messages, undone)
        page.keyboard.press("Control+y")
        expect_text(messages, redone)


def test_the_map_tools_keys_zoom_the_focused_map(page: Any, gateway: Gateway) -> None:
    """+ and - on the focused map zoom it, as the Zoom in and Zoom out buttons do (their aria-keyshortcuts)."""
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
    canvas = page.get_by_role("img", name="Map", exact=True)
    for name, key in [("Zoom in", "+"), ("Zoom out", "-")]:
        assert page.get_by_role("button", name=name, exact=True).get_attribute("aria-keyshortcuts") == key

    def scale() -> float:
        return float(json.loads(canvas.get_attribute("data-camera"))["scale"])

    canvas.focus()
    before = scale()
    page.keyboard.press("+")
    wait_for(lambda: scale() > before * 1.4, what="zoomed in by +")
    page.keyboard.press("-")
    wait_for(lambda: abs(scale() - before) < before * 0.01, what="zoomed back out by -")
