"""The doors (issue 33) as a user meets them: the token beyond loopback, a read-only GUI, viewers and one driver.

``--listen 0.0.0.0:0`` is reached over 127.0.0.1 only (tests send traffic to loopback only). Each gateway here is
``pltf gui`` started for the test; the page checks use Debian's chromium, the platform is the reference server and
what the GUI did is checked over the server's other port.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from pltf.client import OperationState
from pltf.gui.launch import GatewayProcess
from pltf.harness import launch
from tests.gui.conftest import VIEWPORT, Platform, expect_text, wait_for
from tests.gui.fakes import free_port, request, upgrade

READY, RUNNING = OperationState.ST_OP_READY, OperationState.ST_OP_RUNNING

# What a read-only page may still offer: menus, views, zoom and pan, the tabs of the docked windows, reads
# (Refresh map, Read all, Load from platform), the CAN filter, dialogs, the windows in SHOWING. The editors'
# drafting tools edit the page's copy of a document (sending it is a command: checked disabled below). Anything
# else enabled is a command let through.
VIEWING = {
    "Socket", "View", "Parameter", "Edit", "Open Socket", "Open Socket At", "Close Socket", "Map",
    "Hardware Monitor", "View Options", "Plots", "Log", "Wire Inspector", "Platform parameters", "Edit Map",
    "Edit Roadmap", "Refresh map", "Zoom all", "Zoom in", "Zoom out", "Zoom to area", "Pan", "Read all",
    "Filter (id, . = any digit)", "Keyboard shortcuts (?)",
}  # fmt: skip

# every control in the page, hidden panes included, that is not disabled (a disabled fieldset disables its own)
_ENABLED = """() => [...document.querySelectorAll("button, input, select, textarea, [role=menuitem]")]
  .filter((e) => !e.matches(":disabled") && e.getAttribute("aria-disabled") !== "true")
  .map((e) => ({tag: e.tagName.toLowerCase(), type: e.getAttribute("type") || "", role: e.getAttribute("role") || "",
    name: e.getAttribute("aria-label") || e.textContent.trim(),
    editor: e.closest(".map-editor, .roadmap-editor") !== null, pane: e.closest("[id^=pane-]")?.id || "",
    help: e.closest("[role=dialog].help") !== null}))"""
# the docked windows that only show: their switches change the page (the planning obstacles' switch sets a
# parameter of the platform: a command, so it must be disabled like the rest)
SHOWING = {"pane-view-options", "pane-wire", "pane-plots", "pane-log"}
PLAN_OBST = "Obstacles used for planning (ViewPlanObstEnabled)"


def _gateway(tmp_path: Path, target: str, *args: str, listen: str = "127.0.0.1:0") -> GatewayProcess:
    ini = tmp_path / "Network.ini"
    return GatewayProcess(ini, target=target, listen=listen, allow_any_target=False, args=args)


@pytest.fixture(scope="module")
def shared() -> Iterator[Platform]:
    """One reference server for the module's browser tests (a start costs 5-10 s on a loaded machine): the
    read-only test changes nothing on it, so the other test finds it as started whichever runs first."""
    with launch.reference(time_scale=5.0, extra=["--control-port", "0"], start_timeout=60.0) as server:
        p = Platform(server)
        try:
            yield p
        finally:
            p.close()


@pytest.fixture
def context(browser: Any) -> Iterator[Any]:
    ctx = browser.new_context(viewport=VIEWPORT)
    problems: list[str] = []
    ctx.on("weberror", lambda e: problems.append(f"page error: {e.error}"))
    ctx.on("console", lambda m: problems.append(f"console {m.type}: {m.text}") if m.type == "error" else None)
    try:
        yield ctx
    finally:
        ctx.close()
    assert not problems, problems


def _page(context: Any) -> Any:
    pg = context.new_page()
    pg.set_default_timeout(30_000)
    return pg


def _port(gw: GatewayProcess) -> int:
    return int(gw.base.rsplit(":", 1)[1])


def test_beyond_loopback_every_request_needs_the_token(tmp_path: Path) -> None:
    with _gateway(tmp_path, "127.0.0.1:1", listen="0.0.0.0:0") as gw:
        port, token = _port(gw), gw.token
        assert token is not None and len(token) >= 32  # generated with secrets, printed in the URL
        own = {"Host": f"127.0.0.1:{port}"}  # a loopback client: no exception (a local reverse proxy looks local)
        for path in ("/", "/api/targets", f"/?target=127.0.0.1:1&token={'0' * len(token)}"):
            status, body, _ = request(port, path, own)
            assert status == 401, path
            assert "token" in body
        assert upgrade(port, "127.0.0.1:1", own)[0] == 401
        assert request(port, "/api/targets", {**own, "Authorization": f"token {token}"})[0] == 200
        status, _, headers = request(port, f"/?target=127.0.0.1:1&token={token}", own)
        assert status == 200
        cookie = headers["Set-Cookie"]
        assert "HttpOnly" in cookie and "SameSite=Strict" in cookie and token not in cookie
        jar = {**own, "Cookie": cookie.split(";", 1)[0]}
        assert request(port, "/api/targets", jar)[0] == 200
        # the cookie is named with the port: one browser, two gateways on one machine, each keeps its own
        name, value = jar["Cookie"].split("=", 1)
        assert name.endswith(f"_{port}")
        other = {**own, "Cookie": f"{name.removesuffix(str(port))}{port + 1}={value}"}
        assert request(port, "/api/targets", other)[0] == 401
        assert upgrade(port, "127.0.0.1:1", jar)[0] == 101
        # the token does not open the door for a foreign Host
        assert request(port, f"/?token={token}", {"Host": f"evil.example:{port}"})[0] == 403


def test_a_given_token_is_asked_for_on_loopback_too(tmp_path: Path) -> None:
    """--token on a loopback --listen: for a machine shared with other users (docs/security.md)."""
    with _gateway(tmp_path, "127.0.0.1:1", "--token", "s3cret-of-ours") as gw:
        port, own = _port(gw), {"Host": f"127.0.0.1:{_port(gw)}"}
        assert gw.token == "s3cret-of-ours"  # printed in the URL
        assert request(port, "/", own)[0] == 401
        assert request(port, "/?token=s3cret-of-ours", own)[0] == 200


def test_no_token_beyond_loopback_is_warned_about(tmp_path: Path) -> None:
    with _gateway(tmp_path, "127.0.0.1:1", "--no-token", listen="0.0.0.0:0") as gw:
        assert gw.token is None
        assert request(_port(gw), "/", {"Host": f"127.0.0.1:{_port(gw)}"})[0] == 200
        wait_for(lambda: "warning: --no-token" in "\n".join(gw.output), timeout=10, what="the warning")


def test_read_only_offers_no_command_and_the_gateway_refuses_one_sent_by_hand(
    tmp_path: Path, context: Any, shared: Platform
) -> None:
    platform = shared
    with _gateway(tmp_path, platform.target, "--read-only") as gw:
        page = _page(context)
        page.goto(gw.url(platform.target))
        expect_text(page.get_by_role("status", name="Connection"), f"connected to {platform.target}")
        expect_text(page.get_by_role("status", name="Control"), "read-only")
        for name in ("Edit Map", "Edit Roadmap"):  # the editors' panes exist once opened
            page.get_by_role("menuitem", name="Edit", exact=True).click()
            page.get_by_role("menuitem", name=name, exact=True).click()
        page.get_by_role("menuitem", name="Socket", exact=True).click()  # the menu looks at its items
        enabled = page.evaluate(_ENABLED)
        commands = [e for e in enabled if e["name"] not in VIEWING and not _viewing(e)]
        assert commands == [], "\n".join(f"{e}" for e in commands)
        for name in (
            "Init",
            "Start",
            "Stop",
            "Set",
            "Send to platform",
            "Send frame",
            "Shift platform",
            "Target frame",
        ):
            found = page.get_by_role("button", name=name, exact=True, include_hidden=True).all()
            assert found and all(b.is_disabled() for b in found), name
        assert page.get_by_role("checkbox", name=PLAN_OBST, include_hidden=True).is_disabled()
        before = platform.other.get_status()
        refused = page.evaluate(_BY_HAND, platform.target)
        assert [e["telegram"] for e in refused] == ["CMD_MOVE_VEL", "CMD_SET_FRM_PLTF"]
        assert all(e["reason"] == "read_only" for e in refused)
        after = platform.other.get_status()
        # not shifted to (1234, 5678) mm (a platform left running may drift by its localization, never that far)
        for pose in (before, after):
            assert math.hypot(pose.est_x_mm - 1234, pose.est_y_mm - 5678) > 500
        # this gateway has no --allow-any-target: Open Socket At offers the known addresses only ...
        page.keyboard.press("Escape")
        page.get_by_role("menuitem", name="Socket", exact=True).click()
        page.get_by_role("menuitem", name="Open Socket At", exact=True).click()
        dialog = page.get_by_role("dialog", name="Open Socket At")
        expect_text(dialog, "--allow-any-target")
        assert dialog.get_by_role("textbox").count() == 0
        dialog.get_by_role("button", name="Cancel", exact=True).click()
        # ... and a page naming another target is told so, once, in words
        off_list = f"127.0.0.1:{free_port()}"
        page.goto(f"{gw.base}/?target={off_list}")
        expect_text(page.get_by_role("status", name="Connection"), f"{off_list} is not on this GUI's list")


def _viewing(control: dict[str, Any]) -> bool:
    """A tab of a docked window, a view option, an editor's drafting tool, the keyboard help: they change the page,
    not the platform."""
    if control["role"] == "tab" or control["help"] or (control["pane"] in SHOWING and control["name"] != PLAN_OBST):
        return True
    return bool(control["editor"]) and control["name"] != "Send to platform"


# a moving and a changing telegram by hand over the page's own WebSocket, then GET_STATUS (answered: everything
# sent before it has been dealt with); resolves with the refusals
_BY_HAND = """(target) => new Promise((done) => {
  const frame = (id, body) => { const b = new Uint8Array(9 + body.length);
    b.set([0xff, 0x01, 0xfe, 0x02, 0, 0, 0, 1 + body.length, id]); b.set(body, 9); return b; };
  const i32 = (...v) => { const d = new DataView(new ArrayBuffer(4 * v.length));
    v.forEach((x, k) => d.setInt32(4 * k, x)); return new Uint8Array(d.buffer); };
  const refused = [];
  const ws = new WebSocket(`ws://${location.host}/ws?target=${target}`);
  ws.binaryType = "arraybuffer";
  ws.onmessage = (m) => {
    if (typeof m.data !== "string") { ws.close(); done(refused); return; }
    const ev = JSON.parse(m.data);
    if (ev.event === "refused_command") refused.push(ev);
    if (ev.event === "connected") {
      ws.send(frame(24, i32(300, 0)));             // CMD_MOVE_VEL
      ws.send(frame(36, i32(1234, 5678, 0)));      // CMD_SET_FRM_PLTF
      ws.send(frame(18, new Uint8Array(0)));       // CMD_GET_STATUS
    }
  };
  ws.onopen = () => ws.send(JSON.stringify({op: "open"}));
})"""


def test_the_printed_url_opens_the_gui_one_tab_drives_and_another_takes_over_by_the_button(
    tmp_path: Path, context: Any, shared: Platform
) -> None:
    """Beyond loopback with the printed URL (token, then its cookie), two tabs: the first command takes control,
    the other watches with its command buttons disabled and takes over by "Take control"."""
    platform = shared
    with _gateway(tmp_path, platform.target, listen="0.0.0.0:0") as gw:
        assert gw.token is not None
        a, b = _page(context), _page(context)
        for p in (a, b):
            p.goto(gw.url(platform.target))
            expect_text(p.get_by_role("status", name="Connection"), f"connected to {platform.target}")
        assert "token" not in a.url  # now a cookie: out of the address bar
        a.get_by_role("button", name="Init", exact=True).click()  # nobody drove: the first command takes control
        expect_text(a.get_by_role("status", name="Control"), "you drive")
        expect_text(b.get_by_role("status", name="Control"), "drives; you watch")
        wait_for(lambda: platform.other.get_status().operation_state == READY, what="Ready over the other port")
        expect_text(b.get_by_role("status", name="System state"), "Ready")
        start_b = b.get_by_role("button", name="Start", exact=True)
        assert start_b.is_disabled()  # a viewer's command buttons are disabled, whatever the state chart allows
        b.get_by_role("button", name="Take control", exact=True).click()
        expect_text(b.get_by_role("status", name="Control"), "you drive")
        expect_text(a.get_by_role("status", name="Control"), "drives; you watch")
        start_b.click()
        wait_for(lambda: platform.other.get_status().operation_state == RUNNING, what="Running over the other port")
        assert a.get_by_role("button", name="Stop", exact=True).is_disabled()
        b.reload()  # the cookie alone lets the page in again
        expect_text(b.get_by_role("status", name="Connection"), f"connected to {platform.target}")
        stranger = _page(context.browser.new_context())  # no token, no cookie
        try:
            assert stranger.goto(f"{gw.base}/?target={platform.target}").status == 401
        finally:
            stranger.context.close()
