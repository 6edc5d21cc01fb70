"""gui/gateway.py as a viewer meets it (issue 19: "Several browser tabs may watch one platform at once"): tabs
left open do not starve the next one, and a gateway that has logged a lot keeps answering.

The second test is the regression test of the whole-run stall of the GUI tests (session gui19b): the gateway's
stderr went into a pipe nobody read; once some 64 KB of log lines had filled it, the next log call blocked the
gateway's only thread and page loads timed out (the wire inspector and Shutdown Platform, late in the run).
"""

from __future__ import annotations

import urllib.request
from typing import Any

from tests.gui.conftest import VIEWPORT, Gateway, Platform, expect_text, open_gui, wait_for

TABS = 7  # more than chromium's six HTTP connections per host
CLOSES = 2000  # log lines of some 70 bytes: twice what a pipe holds (64 KB)


def test_tabs_left_open_do_not_starve_the_next_one(browser: Any, gateway: Gateway, platform: Platform) -> None:
    context = browser.new_context(viewport=VIEWPORT)
    try:
        tabs = []
        for _ in range(TABS):
            tab = context.new_page()
            open_gui(tab, gateway, platform.target)
            tabs.append(tab)
        one_more = context.new_page()
        open_gui(one_more, gateway, platform.target)
        # every tab still sees the platform live: the status bar of the first one follows a change made elsewhere
        platform.other.set_frm_pltf(1234, 5678, 0)
        for tab in (tabs[0], one_more):
            expect_text(tab.get_by_role("status", name="Estimated pose"), "1234")
    finally:
        context.close()


def test_the_gateway_keeps_answering_after_logging_more_than_a_pipe_holds(page: Any, gateway: Gateway) -> None:
    """Open Socket, Close Socket, many times over one WebSocket: each close is a log line of some 70 bytes."""
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
    page.evaluate(
        """(n) => new Promise((done) => {
            window.__closed = 0;
            const ws = new WebSocket(`ws://${location.host}/ws?target=127.0.0.1:1`);
            ws.onmessage = (m) => { if (typeof m.data === "string" && JSON.parse(m.data).event === "closed")
                window.__closed += 1; };
            ws.onopen = () => { for (let k = 0; k < n; k++) {
                ws.send(JSON.stringify({op: "open"})); ws.send(JSON.stringify({op: "close"})); } done(); };
        })""",
        CLOSES,
    )
    wait_for(lambda: page.evaluate("() => window.__closed") >= CLOSES, timeout=30, what="every close's event")
    assert gateway.log_size() > 2 * 65536  # the harness kept the gateway's log whole, in a file
    with urllib.request.urlopen(gateway.base + "/", timeout=10) as r:
        assert r.status == 200
    open_gui(page, gateway, "127.0.0.1:1", connected=False)
