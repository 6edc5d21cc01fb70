"""The GUI's HTTP side: the built web application, one WebSocket per browser tab, the known addresses.

Rules:
- ``GET /`` and ``/assets/...`` serve the built front end (gui/static, made by ``make gui``).
- ``GET /ws?target=HOST:PORT`` upgrades to a WebSocket attached to the ``PlatformLink`` of that target (one per
  target, shared by every tab). Binary messages are request frames (tab -> platform) and reply frames
  (platform -> tab), one frame per message; text messages are JSON: ``{"op": "open"}`` / ``{"op": "close"}``
  from the tab, events (link.py) to it. ``{"op": "truth", "control": "HOST:PORT"}`` starts the optional
  ground-truth reader of the tab (truth.py).
- ``GET /api/targets`` lists the known addresses (guide 5.2: "Network.ini"), the default target first, and the
  fleet (issue 30: ``pltf gui --target A --target B`` or ``--fleet FILE``) as ``{"name", "target"}`` each, the
  page's names of its platforms; every platform of the fleet is on the list of targets. ``POST /api/targets``
  with ``{"target": "HOST:PORT"}`` adds one to the file.
- Who may come in (doors.py, issue 33): every request passes the Host, Origin and token checks first; a target
  not on the list (targets.py) is refused before any connection attempt; one tab drives, the others watch
  (control.py; ``{"op": "take"}`` is "Take control").
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
from pathlib import Path
from typing import Any

from aiohttp import WSMsgType, web

from pltf.gui.doors import Doors
from pltf.gui.link import PlatformLink, parse_target
from pltf.gui.network_ini import NetworkIni
from pltf.gui.recorded import Recording
from pltf.gui.recorded import add_routes as add_recording_routes
from pltf.gui.targets import TargetList
from pltf.gui.truth import TruthReader
from pltf.gui.validate import add_routes as add_validate_routes

log = logging.getLogger("pltf.gui")
# PLTF_GUI_STATIC: another build of the front end (e.g. `vite build --outDir DIR` while developing one part of it)
STATIC = Path(os.environ.get("PLTF_GUI_STATIC") or Path(__file__).resolve().parent / "static")
LINKS = web.AppKey("links", dict)
CONFIG = web.AppKey("config", dict)
TARGETS = web.AppKey("targets", TargetList)


def _link(app: web.Application, target: str) -> PlatformLink:
    links: dict[str, PlatformLink] = app[LINKS]
    link = links.get(target)
    if link is None:

        def gone(lk: PlatformLink) -> None:
            links.pop(lk.target, None)

        link = links[target] = PlatformLink(target, **app[CONFIG]["link"], on_idle=gone)
    return link


def _label(request: web.Request) -> str:
    """How the other tabs see this one: "tab N (ADDRESS)"."""
    config = request.app[CONFIG]
    config["tabs"] += 1
    return f"tab {config['tabs']} ({request.remote or 'unknown address'})"


async def _refuse_target(request: web.Request, target: str, why: str) -> web.WebSocketResponse:
    """Said on the WebSocket, so the page shows it; no link, no connection attempt (targets.py)."""
    ws = web.WebSocketResponse()
    await ws.prepare(request)
    log.warning("refused a tab's target: %s", why)
    await ws.send_str(json.dumps({"event": "target_refused", "target": target, "message": why}))
    await ws.close(code=4003, message=b"target not allowed")
    return ws


async def websocket(request: web.Request) -> web.StreamResponse:
    target = request.query.get("target") or request.app[CONFIG]["target"]
    try:
        parse_target(target)
    except ValueError as exc:
        raise web.HTTPBadRequest(text=str(exc)) from None
    if (why := request.app[TARGETS].refusal(target)) is not None:
        return await _refuse_target(request, target, why)
    ws = web.WebSocketResponse(max_msg_size=32 * 1024 * 1024, heartbeat=20.0)
    await ws.prepare(request)
    link = _link(request.app, target)
    tab = object()
    queue: asyncio.Queue[bytes | dict[str, Any] | None] = asyncio.Queue()
    link.attach(tab, queue.put_nowait, _label(request))

    async def pump() -> None:
        while (item := await queue.get()) is not None:
            if ws.closed:
                return
            if isinstance(item, bytes):
                await ws.send_bytes(item)
            else:
                await ws.send_str(json.dumps(item))

    pumping = asyncio.get_running_loop().create_task(pump())
    truth: list[TruthReader] = []
    try:
        async for msg in ws:
            if msg.type == WSMsgType.BINARY:
                link.submit(tab, msg.data)
            elif msg.type == WSMsgType.TEXT:
                _command(link, tab, msg.data, queue.put_nowait, truth, request.app[TARGETS])
    finally:
        for reader in truth:
            reader.stop()
        link.detach(tab)
        queue.put_nowait(None)
        await pumping
    return ws


def _command(
    link: PlatformLink, tab: object, text: str, send: Any, truth: list[TruthReader], allowed: TargetList
) -> None:
    try:
        body = json.loads(text)
        op = body.get("op")
    except (ValueError, AttributeError):
        op = None
    if op == "truth":
        _truth(str(body.get("control", "")), send, truth, allowed)
    elif op == "open":
        link.open()
    elif op == "close":
        if link.may_close(tab):
            link.close("socket closed by a viewer", by="viewer")
    elif op == "take":
        link.take(tab)
    elif op == "stats":
        send({"event": "stats", "target": link.target, "state": link.state, **link.stats.snapshot()})
    else:
        send({"event": "bad_request", "target": link.target, "message": f"unknown operation in {text[:80]!r}"})


def _truth(control: str, send: Any, truth: list[TruthReader], allowed: TargetList) -> None:
    """The ground truth's reader; its control channel is a target like any other: on the list (targets.py), or
    a page could probe this machine's ports through it."""
    for reader in truth:
        reader.stop()
    truth.clear()
    try:
        if (why := allowed.refusal(control)) is not None:
            raise ValueError(why)
        truth.append(TruthReader(control, send))
    except ValueError as exc:
        send({"event": "truth_lost", "control": control, "detail": str(exc), "message": str(exc)})


async def targets(request: web.Request) -> web.Response:
    ini: NetworkIni = request.app[CONFIG]["ini"]
    any_target = request.app[TARGETS].any_target
    if request.method == "POST":
        if not any_target:  # else a page could put any address on the list (targets.py)
            raise web.HTTPForbidden(
                text="adding an address from the page needs `pltf gui --allow-any-target`; "
                f"or add it to {ini.path} yourself"
            )
        try:
            body = await request.json()
            ini.add(str(body["target"]))
        except (ValueError, KeyError, TypeError) as exc:
            raise web.HTTPBadRequest(text=f'expected {{"target": "HOST:PORT"}}: {exc}') from None
    default = request.app[CONFIG]["target"]  # None: a recording is shown (pltf gui --session), no target
    known = [*([default] if default else []), *(t for t in ini.targets() if t != default)]
    fleet = [{"name": name, "target": t} for name, t in request.app[CONFIG]["fleet"]]
    return web.json_response({"default": default, "targets": known, "any": any_target, "fleet": fleet})


async def index(request: web.Request) -> web.StreamResponse:
    page = STATIC / "index.html"
    if not page.is_file():
        return web.Response(status=503, text="the web application is not built: run `make gui` in the toolkit")
    return web.FileResponse(page, headers={"Cache-Control": "no-cache"})


async def _shutdown(app: web.Application) -> None:
    for link in list(app[LINKS].values()):
        link.close("gateway stopped", by="gateway")


def make_app(
    target: str | None,
    ini: NetworkIni,
    *,
    reply_timeout: float | None = None,
    backoff: tuple[float, ...] | None = None,
    doors: Doors | None = None,
    allowed: TargetList | None = None,
    read_only: bool = False,
    fleet: tuple[tuple[str, str], ...] = (),
    recording: Recording | None = None,
) -> web.Application:
    """``doors`` and ``allowed`` (the targets) default to a loopback gateway that connects only to ``target`` and
    the addresses of Network.ini. With ``recording`` (``pltf gui --session``, recorded.py) there is no /ws: the
    page shows the recording and nothing reaches a platform."""
    app = web.Application(middlewares=[(doors or Doors()).middleware()])
    app[TARGETS] = allowed or TargetList(target or "", ini)
    link_options: dict[str, Any] = {"read_only": read_only}
    if reply_timeout is not None:
        link_options["reply_timeout"] = reply_timeout
    if backoff is not None:
        link_options["backoff"] = backoff
    app[LINKS] = {}
    app[CONFIG] = {"target": target, "ini": ini, "link": link_options, "tabs": 0, "fleet": fleet}
    app.router.add_get("/", index)
    if recording is None:
        app.router.add_get("/ws", websocket)
    else:
        add_recording_routes(app, recording)
    app.router.add_route("*", "/api/targets", targets)
    add_validate_routes(app)  # the editors' check before sending (issue 20)
    if (STATIC / "assets").is_dir():
        app.router.add_static("/assets", STATIC / "assets")
    app.on_shutdown.append(_shutdown)
    return app
