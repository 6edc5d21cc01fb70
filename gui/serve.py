"""Run the gateway: ``pltf gui --target HOST:PORT [--listen 127.0.0.1:8080] [--open]``.

Rules: one line on stdout says where the GUI is (``gui serving at http://HOST:PORT/?target=...``: tests and
``make demo`` read it); user errors are one line on stderr and exit 2; SIGINT/SIGTERM stop it cleanly.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import signal
import sys
import webbrowser
from pathlib import Path
from urllib.parse import quote

from aiohttp import web

from pltf.gui.gateway import STATIC, make_app
from pltf.gui.network_ini import NetworkIni, default_path

log = logging.getLogger("pltf.gui")


async def serve(
    target: str,
    listen: str,
    ini_path: Path | None = None,
    open_browser: bool = False,
    reply_timeout: float | None = None,
) -> int:
    host, port = parse_listen(listen)
    app = make_app(target, NetworkIni(ini_path or default_path()), reply_timeout=reply_timeout)
    runner = web.AppRunner(app, access_log=None, handle_signals=False)
    await runner.setup()
    site = web.TCPSite(runner, host, port)
    try:
        await site.start()
    except OSError as exc:
        await runner.cleanup()
        print(f"pltf gui: error: cannot listen on {listen}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    sockets = getattr(site._server, "sockets", None) or []
    bound = sockets[0].getsockname()[1] if sockets else port
    url = f"http://{host}:{bound}/?target={quote(target)}"
    if not (STATIC / "index.html").is_file():
        log.warning("the web application is not built (%s missing): run `make gui`", STATIC / "index.html")
    print(f"gui serving at {url}", flush=True)
    if open_browser:
        webbrowser.open(url)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError):
            loop.add_signal_handler(sig, stop.set)
    await stop.wait()
    await runner.cleanup()
    return 0


def parse_listen(text: str) -> tuple[str, int]:
    host, sep, port = text.rpartition(":")
    if not sep or not port.isdigit() or not 0 <= int(port) < 65536:
        raise ValueError(f"expected HOST:PORT (port 0: any free port), got {text!r}")
    return host or "127.0.0.1", int(port)
