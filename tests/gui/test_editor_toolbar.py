"""The editors' toolbar (gui/web/src/editor/toolbar.ts, guide 5.4 and 5.5): both editors' toolbars are named,
and of their tools exactly the one picked last is pressed. No platform is needed: the editors work offline."""

from __future__ import annotations

from typing import Any

import pytest

from tests.gui.conftest import Gateway, open_gui

EDITORS = {
    "Edit Map": (
        "Map editor",
        ["Edit objects", "Add a line", "Trim", "Extend", "Make parallel", "Make orthogonal"],
        "New map",
    ),
    "Edit Roadmap": ("Roadmap editor", ["Edit stations", "Add a station", "Add an edge"], "New roadmap"),
}


@pytest.mark.parametrize("menu", list(EDITORS))
def test_one_tool_of_each_editor_s_toolbar_is_pressed(page: Any, gateway: Gateway, menu: str) -> None:
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
    page.get_by_role("menuitem", name="Edit", exact=True).click()
    page.get_by_role("menuitem", name=menu, exact=True).click()
    name, tools, action = EDITORS[menu]
    bar = page.get_by_role("toolbar", name=name, exact=True)

    def pressed() -> list[str]:
        states = [bar.get_by_role("button", name=t, exact=True).get_attribute("aria-pressed") for t in tools]
        return [t for t, state in zip(tools, states, strict=True) if state == "true"]

    assert pressed() == [tools[0]]  # the editor opens on selecting
    for tool in [*tools[1:], tools[0]]:
        bar.get_by_role("button", name=tool, exact=True).click()
        assert pressed() == [tool]
    # an action is not a tool: it leaves the pressed one alone
    bar.get_by_role("button", name=action, exact=True).click()
    assert pressed() == [tools[0]]
