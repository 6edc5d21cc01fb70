"""The help overlay (issue 35) in Debian's chromium: `?` opens a list of the GUI's keyboard shortcuts, each with
what it does in the guide's words; Escape closes it and gives the focus back; the header's Help button opens it
too; in German it says the same in German. No platform is needed: the list is there offline."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from tests.gui.conftest import Gateway, open_gui

# keys as the list shows them (kbd texts joined by +) and a part of what the guide says each does
EXPECTED = {
    "?": "list of keyboard shortcuts",
    "Ctrl+O": "Open Socket",
    "Alt+I": "self test",
    "Alt+S": 'operation state changes into the state "Moving"',
    "Alt+B": 'changes into the state "Break"',
    "Alt+C": "continue the execution of a platform motion mode",
    "Alt+X": "stop the motion of the platform",
    "Arrow keys": "CMD_MOVE_VEL",
    "H J K L": "scroll the map",
    "+": "Zoom in",
    "Ctrl+Z": "Undo",
    "Ctrl+Y": "Redo",
}


def rows(dialog: Any) -> dict[str, str]:
    """The overlay's table: each row's keys (kbd texts, + between those pressed together) -> what it does."""
    got: list[list[str]] = dialog.locator("tbody tr").evaluate_all(
        """trs => trs.map(tr => [tr.cells[0].textContent, tr.cells[1].textContent])"""
    )
    return {re.sub(r"\s*\+\s*", "+", keys.split(" or ")[0].strip()): what for keys, what in got}


def test_question_mark_lists_the_shortcuts_and_escape_closes_it(page: Any, gateway: Gateway, artifacts: Path) -> None:
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
    dialog = page.get_by_role("dialog", name="Keyboard shortcuts")
    assert dialog.count() == 0 or not dialog.is_visible()
    page.get_by_role("img", name="Map").focus()
    page.keyboard.press("?")
    dialog.wait_for(state="visible")
    page.screenshot(path=str(artifacts / "help-overlay.png"))
    listed = rows(dialog)
    for keys, words in EXPECTED.items():
        assert keys in listed, f"{keys} is not listed: {sorted(listed)}"
        assert words.lower() in listed[keys].lower(), (keys, listed[keys])
    # modal: a key pressed while it is open does not reach the map (h pans it when the map has the focus)
    camera = page.get_by_role("img", name="Map").get_attribute("data-camera")
    page.keyboard.press("h")
    page.keyboard.press("Escape")
    dialog.wait_for(state="hidden")
    assert page.get_by_role("img", name="Map").get_attribute("data-camera") == camera
    assert page.evaluate("() => document.activeElement?.getAttribute('aria-label')") == "Map"  # the focus is back


def test_the_help_button_opens_it_and_its_close_button_closes_it(page: Any, gateway: Gateway) -> None:
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
    page.get_by_role("button", name="Keyboard shortcuts (?)").click()
    dialog = page.get_by_role("dialog", name="Keyboard shortcuts")
    dialog.wait_for(state="visible")
    assert len(rows(dialog)) >= len(EXPECTED)
    dialog.get_by_role("button", name="Close").click()
    dialog.wait_for(state="hidden")


def test_a_question_mark_typed_into_a_field_is_a_character(page: Any, gateway: Gateway) -> None:
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
    page.get_by_role("menuitem", name="Socket", exact=True).click()
    page.get_by_role("menuitem", name="Open Socket At", exact=True).click()
    field = page.get_by_role("textbox", name="Address (HOST:PORT)")
    field.focus()
    page.keyboard.press("?")
    assert field.input_value() == "?"
    assert not page.get_by_role("dialog", name="Keyboard shortcuts").is_visible()


def test_in_german_it_lists_the_same_shortcuts_in_german(page: Any, gateway: Gateway) -> None:
    page.add_init_script("localStorage.setItem('pltf.lang', 'de')")
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
    page.keyboard.press("?")
    dialog = page.get_by_role("dialog", name="Tastenkürzel")
    dialog.wait_for(state="visible")
    listed = rows(dialog)
    assert "Strg+O" in listed
    assert "Moving" in listed["Alt+S"] and "Betriebszustand" in listed["Alt+S"]
    assert len(listed) >= len(EXPECTED)
    page.keyboard.press("Escape")
    dialog.wait_for(state="hidden")
