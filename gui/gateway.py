"""The GUI's HTTP side: the built web application, one WebSocket per browser tab, the known addresses.

Rules:
- ``GET /`` and ``/assets/...`` serve the built front end (gui/static, made by ``make gui``).
- ``GET /ws?target=HOST:PORT`` upgrades to a WebSocket attached to the ``PlatformLink`` of that target (one per
  target, shared by every tab). Binary messages are request frames (tab -> platform) and reply frames
  (platform -> tab), one frame per message; text messages are JSON: ``{"op": "open"}`` / ``{"op": "close"}``
  from the tab, events (link.py) to it. ``{"op": "truth", "control": "HOST:PORT"}`` starts the optional
  ground-truth reader of the tab (truth.py).
- ``GET /api/targets`` lists the known addresses (guide 5.2: "Network.ini"), the default target first;
  ``POST /api/targets`` with ``{"target": "HOST:PORT"}`` adds one to the file.
- A WebSocket from another origin is refused: a page from elsewhere must not drive the platform.
"""

from __future__ import annotations

import asyncio
import json
import logging
from pathlib import Path
from typing import Any

from aiohttp import WSMsgType, web

from pltf.gui.link import PlatformLink, parse_target
from pltf.gui.network_ini import NetworkIni
from pltf.gui.truth import TruthReader
from pltf.gui.validate import add_routes as add_validate_routes

log = logging.getLogger("pltf.gui")
STATIC = Path(__file__).resolve().parent / "static"
LINKS = web.AppKey("links", dict)
CONFIG = web.AppKey("config", dict)


def _same_origin(request: web.Request) -> bool:
    origin = request.headers.get("Origin")
    if origin is None:
        return True  # not a browser page (a test client, curl)
    return origin.split("://", 1)[-1] == request.host


def _link(app: web.Application, target: str) -> PlatformLink:
    links: dict[str, PlatformLink] = app[LINKS]
    link = links.get(target)
    if link is None:

        def gone(lk: PlatformLink) -> None:
            links.pop(lk.target, None)

        link = links[target] = PlatformLink(target, **app[CONFIG]["link"], on_idle=gone)
    return link


async def websocket(request: web.Request) -> web.StreamResponse:
    if not _same_origin(request):
        raise web.HTTPForbidden(text="WebSocket from another origin refused")
    target = request.query.get("target") or request.app[CONFIG]["target"]
    try:
        parse_target(target)
    except ValueError as exc:
        raise web.HTTPBadRequest(text=str(exc)) from None
    ws = web.WebSocketResponse(max_msg_size=32 * 1024 * 1024, heartbeat=20.0)
    await ws.prepare(request)
    link = _link(request.app, target)
    tab = object()
    queue: asyncio.Queue[bytes | dict[str, Any] | None] = asyncio.Queue()
    link.attach(tab, queue.put_nowait)

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
                _command(link, msg.data, queue.put_nowait, truth)
    finally:
        for reader in truth:
            reader.stop()
        link.detach(tab)
        queue.put_nowait(None)
        await pumping
    return ws


def _command(link: PlatformLink, text: str, send: Any, truth: list[TruthReader]) -> None:
    try:
        body = json.loads(text)
        op = body.get("op")
    except (ValueError, AttributeError):
        op = None
    if op == "truth":
        _truth(link, str(body.get("control", "")), send, truth)
    elif op == "open":
        link.open()
    elif op == "close":
        link.close("socket closed by a viewer", by="viewer")
    elif op == "stats":
        send({"event": "stats", "target": link.target, "state": link.state, **link.stats.snapshot()})
    else:
        send({"event": "bad_request", "target": link.target, "message": f"unknown operation in {text[:80]!r}"})


def _truth(link: PlatformLink, control: str, send: Any, truth: list[TruthReader]) -> None:
    for reader in truth:
        reader.stop()
    truth.clear()
    try:
        truth.append(TruthReader(control, send))
    except ValueError as exc:
        send({"event": "truth_lost", "control": control, "detail": str(exc), "message": str(exc)})


async def targets(request: web.Request) -> web.Response:
    ini: NetworkIni = request.app[CONFIG]["ini"]
    if request.method == "POST":
        if not _same_origin(request):
            raise web.HTTPForbidden(text="request from another origin refused")
        try:
            body = await request.json()
            ini.add(str(body["target"]))
        except (ValueError, KeyError, TypeError) as exc:
            raise web.HTTPBadRequest(text=f'expected {{"target": "HOST:PORT"}}: {exc}') from None
    default = request.app[CONFIG]["target"]
    known = [default, *(t for t in ini.targets() if t != default)]
    return web.json_response({"default": default, "targets": known})


async def index(request: web.Request) -> web.StreamResponse:
    page = STATIC / "index.html"
    if not page.is_file():
        return web.Response(status=503, text="the web application is not built: run `make gui` in the toolkit")
    return web.FileResponse(page, headers={"Cache-Control": "no-cache"})


async def _shutdown(app: web.Application) -> None:
    for link in list(app[LINKS].values()):
        link.close("gateway stopped", by="gateway")


def make_app(
    target: str, ini: NetworkIni, *, reply_timeout: float | None = None, backoff: tuple[float, ...] | None = None
) -> web.Application:
    app = web.Application()
    link_options: dict[str, Any] = {}
    if reply_timeout is not None:
        link_options["reply_timeout"] = reply_timeout
    if backoff is not None:
        link_options["backoff"] = backoff
    app[LINKS] = {}
    app[CONFIG] = {"target": target, "ini": ini, "link": link_options}
    app.router.add_get("/", index)
    app.router.add_get("/ws", websocket)
    app.router.add_route("*", "/api/targets", targets)
    add_validate_routes(app)  # the editors' check before sending (issue 20)
    if (STATIC / "assets").is_dir():
        app.router.add_static("/assets", STATIC / "assets")
    app.on_shutdown.append(_shutdown)
    return app
