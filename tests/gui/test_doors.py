"""Who may come in (issue 33, gui/doors.py, gui/targets.py): a page of another site, a target off the list.

Each refusal is checked on the side that matters: the HTTP status the client gets, and on the target's side a
``Recorder`` that counts every connection and records every telegram (none may arrive). Each test also shows its
observation works: the allowed request next to the refused one does reach the target.
The gateway is ``pltf gui`` on 127.0.0.1 with its defaults (no --allow-any-target); a test allows its recorder by
adding it to Network.ini, which the gateway reads at each request (guide 5.2).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest

from pltf.gui.launch import GatewayProcess
from pltf.gui.network_ini import NetworkIni
from tests.gui.fakes import MOVE_VEL, Recorder, Tab, free_port, request, run, upgrade


@pytest.fixture(scope="module")
def gui(tmp_path_factory: pytest.TempPathFactory) -> Iterator[GatewayProcess]:
    ini = tmp_path_factory.mktemp("doors") / "Network.ini"
    with GatewayProcess(ini, allow_any_target=False) as gw:
        yield gw


@pytest.fixture
def recorder(gui: GatewayProcess) -> Iterator[Recorder]:
    """A platform on the gateway's list (added to Network.ini)."""
    with Recorder() as rec:
        NetworkIni(gui.ini).add(rec.target)
        yield rec


def _port(gui: GatewayProcess) -> int:
    return int(gui.base.rsplit(":", 1)[1])


def test_a_foreign_host_is_refused_and_nothing_reaches_the_platform(gui: GatewayProcess, recorder: Recorder) -> None:
    port = _port(gui)
    evil = {"Host": f"evil.example:{port}", "Origin": f"http://evil.example:{port}"}  # DNS rebinding: both match
    status, body, _ = request(port, "/", evil)
    assert status == 403 and "--allow-host evil.example" in body
    assert request(port, "/api/targets", evil)[0] == 403
    status, body, _ = upgrade(port, recorder.target, evil)
    assert status == 403 and "--allow-host" in body
    # a page's request need not carry an Origin (a navigation, an image): the Host alone turns it away
    no_origin = {"Host": evil["Host"]}
    assert request(port, "/", no_origin)[0] == 403
    status, body, _ = upgrade(port, recorder.target, no_origin)
    assert status == 403 and "--allow-host evil.example" in body

    async def rebinding_tab_then_ours() -> list[str]:
        # the same page's script with aiohttp's own headers: refused before any link is made
        try:
            await Tab.open(gui.base, recorder.target, evil)
        except Exception as exc:  # aiohttp's handshake error carries the status
            assert "403" in str(exc), exc
        else:
            raise AssertionError("a WebSocket with a foreign Host was let in")
        seen = list(recorder.received)
        tab = await Tab.open(gui.base, recorder.target)  # our own page: Host 127.0.0.1:PORT
        await tab.op("open")
        await tab.event("connected")
        await tab.status()
        await tab.close()
        return seen

    assert run(rebinding_tab_then_ours) == []  # nothing had reached the platform before our own tab
    assert recorder.connects == 1 and recorder.received == ["CMD_GET_STATUS"]
    said = [line.split("WARNING", 1)[-1].strip() for line in gui.output if "evil.example" in line]
    assert said and len(said) == len(set(said))  # the gateway's log says each refusal, once


def test_an_origin_is_checked_against_the_allowed_hosts_not_the_host_header(gui: GatewayProcess) -> None:
    port = _port(gui)
    target = "127.0.0.1:1"  # the gateway's --target: on its list
    own = {"Host": f"127.0.0.1:{port}"}
    for origin in (f"http://evil.example:{port}", f"http://127.0.0.1:{port + 1}", "null"):
        status, body, _ = upgrade(port, target, {**own, "Origin": origin})
        assert status == 403, origin
        assert "not this GUI's page" in body
    for origin in (f"http://127.0.0.1:{port}", f"http://localhost:{port}"):
        assert upgrade(port, target, {**own, "Origin": origin})[0] == 101, origin
    assert request(port, "/", {"Host": f"localhost:{port}"})[0] == 200  # no Origin: not a page, no token here


def test_a_target_off_the_list_is_refused_before_any_connection_attempt(gui: GatewayProcess) -> None:
    with Recorder() as listening:
        closed = f"127.0.0.1:{free_port()}"

        async def ask(target: str) -> dict[str, object]:
            tab = await Tab.open(gui.base, target)
            await tab.op("open")  # would connect if the tab had been let in
            event = await tab.event("target_refused")
            await tab.close()
            return event

        async def truth() -> dict[str, object]:  # the ground truth's control channel is a target too
            tab = await Tab.open(gui.base, "127.0.0.1:1")
            await tab.op("truth", control=listening.target)
            event = await tab.event("truth_lost")
            await tab.close()
            return event

        open_port, closed_port = run(lambda: ask(listening.target)), run(lambda: ask(closed))
        assert "--allow-target" in str(run(truth)["message"])
        assert listening.connects == 0
        assert "--allow-target" in str(open_port["message"])
        # the page learns nothing about the port: both events say the same but for the address
        assert json.dumps(open_port).replace(listening.target, "X") == json.dumps(closed_port).replace(closed, "X")

        NetworkIni(gui.ini).add(listening.target)  # the user adds it to Network.ini: allowed at once

        async def allowed() -> None:
            tab = await Tab.open(gui.base, listening.target)
            await tab.op("open")
            await tab.event("connected")
            await tab.status()  # the platform has served this connection (it counts a connection as it serves it)
            await tab.close()

        run(allowed)
        assert listening.connects == 1  # this one, and none of the refused tabs before it


def test_adding_an_address_from_the_page_needs_allow_any_target(gui: GatewayProcess) -> None:
    port = _port(gui)
    before = Path(gui.ini).read_text(encoding="utf-8") if Path(gui.ini).exists() else ""
    body = json.dumps({"target": "10.1.2.3:10000"})
    conn_headers = {"Host": f"127.0.0.1:{port}", "Content-Type": "application/json", "Content-Length": str(len(body))}
    status, text, _ = _post(port, "/api/targets", conn_headers, body)
    assert status == 403 and "--allow-any-target" in text
    after = Path(gui.ini).read_text(encoding="utf-8") if Path(gui.ini).exists() else ""
    assert after == before
    status, text, _ = request(port, "/api/targets", {"Host": f"127.0.0.1:{port}"})
    assert status == 200 and json.loads(text)["any"] is False


def _post(port: int, path: str, headers: dict[str, str], body: str) -> tuple[int, str, object]:
    import http.client

    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    try:
        conn.putrequest("POST", path, skip_host=True, skip_accept_encoding=True)
        for k, v in headers.items():
            conn.putheader(k, v)
        conn.endheaders(body.encode())
        r = conn.getresponse()
        return r.status, r.read().decode(), r.headers
    finally:
        conn.close()


def test_one_tab_drives_the_others_watch_and_take_over_only_by_asking(gui: GatewayProcess, recorder: Recorder) -> None:
    async def two_tabs() -> None:
        a = await Tab.open(gui.base, recorder.target)
        b = await Tab.open(gui.base, recorder.target)
        await a.op("open")
        await a.event("connected")
        await b.event("connected")
        await a.frame(MOVE_VEL)  # nobody drove: the first command takes control
        a_drives = await a.event("control", you=True)
        seen_by_b = await b.event("control", you=False)
        assert seen_by_b["holder"] == a_drives["holder"] and "127.0.0.1" in str(seen_by_b["holder"])
        await b.frame(MOVE_VEL)  # a viewer's command: refused by the gateway
        refused = await b.event("refused_command", reason="viewer")
        assert "CMD_MOVE_VEL" in str(refused["message"]) and "take control" in str(refused["message"])
        await b.status()  # reads are served; everything b sent before has been dealt with
        assert recorder.received.count("CMD_MOVE_VEL") == 1
        await b.op("close")  # Close Socket would cut the driver off: refused too
        await b.event("refused_command", reason="viewer")
        await b.op("take")  # the explicit action
        await b.event("control", you=True)
        await a.event("control", you=False)
        await b.frame(MOVE_VEL)
        await a.frame(MOVE_VEL)
        await a.event("refused_command", reason="viewer")
        await a.status()
        await b.status()
        assert recorder.received.count("CMD_MOVE_VEL") == 2
        await b.close()  # the driver leaves: control is free again
        await a.event("control", holder=None)
        await a.close()

    run(two_tabs)
    assert recorder.connects == 1  # one connection for both tabs (guide 4.2)
