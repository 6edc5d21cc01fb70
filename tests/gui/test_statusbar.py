"""The status bar (gui/web/src/panels/statusbar.ts) against the reference server: a readout is written when its
value changes and only then. An identical write still makes the browser lay out and paint the page, 20 times a
second at the default polling; on a loaded machine that work delayed the replies and the poll (bench_gui.py)."""

from __future__ import annotations

from typing import Any

from tests.gui.conftest import Gateway, Platform, expect_text, open_gui, wait_for
from tests.gui.test_app import button, readout

WATCH_JS = """() => {
  window.__writes = 0;
  window.__statuses = 0;
  const out = document.querySelector('output[aria-label="System state"]');
  new MutationObserver((records) => { window.__writes += records.length; })
    .observe(out, { childList: true, characterData: true, subtree: true });
  window.pltf.session.status.subscribe(() => { window.__statuses += 1; }, false);
}"""


def test_a_readout_is_written_only_when_its_value_changes(page: Any, gateway: Gateway, platform: Platform) -> None:
    open_gui(page, gateway, platform.target)
    expect_text(readout(page, "System state"), "Not initialized")
    page.evaluate(WATCH_JS)
    wait_for(lambda: page.evaluate("() => window.__statuses") >= 10, what="ten status telegrams")
    assert page.evaluate("() => window.__writes") == 0  # the same state ten times: not written again
    button(page, "Init").click()
    expect_text(readout(page, "System state"), "Ready")
    assert page.evaluate("() => window.__writes") >= 1
