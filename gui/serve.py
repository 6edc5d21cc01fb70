"""Run the gateway: ``pltf gui --target HOST:PORT [--listen 127.0.0.1:8080] [--open]`` and the doors' flags, or
``pltf gui --session FILE``: a recording, without a platform (recorded.py).

Rules: one line on stdout says where the GUI is (``gui serving at http://HOST:PORT/?target=...``, with
``&token=...`` when a token is needed: tests and ``make demo`` read it; a recording's page is
``/?recording=FILE``); under a wildcard listen (0.0.0.0, ::) that line names 127.0.0.1 and the next says how
other machines reach it. A listen beyond loopback without a
token is warned about on stderr (``--no-token``). User errors are one line on stderr and exit 2; SIGINT/SIGTERM
stop it cleanly.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import signal
import sys
import webbrowser
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import urlencode

from aiohttp import web

from pltf.gui.doors import Doors, is_loopback, new_token
from pltf.gui.gateway import STATIC, make_app
from pltf.gui.network_ini import NetworkIni, default_path
from pltf.gui.recorded import Recording
from pltf.gui.targets import TargetList

log = logging.getLogger("pltf.gui")


@dataclass(frozen=True)
class Options:
    """The doors of ``pltf gui`` (issue 33, docs/security.md), as the command line gives them."""

    allow_hosts: tuple[str, ...] = ()
    allow_targets: tuple[str, ...] = ()
    allow_any_target: bool = False
    token: str | None = None
    no_token: bool = False
    read_only: bool = False

    def token_for(self, listen_host: str) -> str | None:
        """The token the gateway asks for: given, generated beyond loopback, none on loopback or --no-token."""
        if self.no_token:
            return None
        if self.token is not None:
            return self.token
        return None if is_loopback(listen_host) else new_token()


async def serve(
    target: str | None,
    listen: str,
    ini_path: Path | None = None,
    open_browser: bool = False,
    reply_timeout: float | None = None,
    options: Options | None = None,
    fleet: tuple[tuple[str, str], ...] = (),
    recording: Recording | None = None,
) -> int:
    """``fleet``: (name, HOST:PORT) of every platform when there are several (issue 30), ``target`` the first;
    ``recording``: the page shows it; ``target`` is then None (no platform: no /ws, nothing connected to)."""
    options = options or Options()
    host, port = parse_listen(listen)
    ini = NetworkIni(ini_path or default_path())
    doors = Doors(host, frozenset(options.allow_hosts), options.token_for(host))
    allowed = frozenset(options.allow_targets) | {t for _, t in fleet}  # every platform of the fleet: on the list
    targets = TargetList(target or "", ini, allowed, options.allow_any_target)  # "": no /ws asks it
    app = make_app(
        target,
        ini,
        reply_timeout=reply_timeout,
        doors=doors,
        allowed=targets,
        read_only=options.read_only,
        fleet=fleet,
        recording=recording,
    )
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
    url = _url(host, bound, [t for _, t in fleet] or [target or ""], doors.token, recording)
    if not (STATIC / "index.html").is_file():
        log.warning("the web application is not built (%s missing): run `make gui`", STATIC / "index.html")
    _warn(host, bound, options, doors)
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


def _url(host: str, port: int, targets: list[str], token: str | None, recording: Recording | None = None) -> str:
    """The page's address: ``?target=A`` (a fleet: ``?target=A&target=B...``, the page opens one session each;
    a recording: ``?recording=FILE``, its name only)."""
    shown = "127.0.0.1" if Doors(host).wildcard else host
    shown = f"[{shown}]" if ":" in shown else shown
    pages = [("recording", recording.path.name)] if recording is not None else [("target", t) for t in targets]
    query = pages + ([("token", token)] if token is not None else [])
    return f"http://{shown}:{port}/?{urlencode(query, safe=':[]')}"


def _warn(host: str, port: int, options: Options, doors: Doors) -> None:
    if Doors(host).wildcard:
        print(
            f"pltf gui: other machines reach it at this machine's addresses, port {port} (a name instead of an "
            "address needs --allow-host NAME)",
            file=sys.stderr,
            flush=True,
        )
    if doors.token is None and not is_loopback(host):
        print(
            "pltf gui: warning: --no-token: whoever reaches this address can drive the platform; "
            "use it only on a trusted network or behind a proxy that authenticates (docs/security.md)",
            file=sys.stderr,
            flush=True,
        )
    if options.read_only:
        print("pltf gui: read-only: the GUI sends no command that moves or changes the platform", file=sys.stderr)


def parse_listen(text: str) -> tuple[str, int]:
    host, sep, port = text.rpartition(":")
    if not sep or not port.isdigit() or not 0 <= int(port) < 65536:
        raise ValueError(f"expected HOST:PORT (port 0: any free port), got {text!r}")
    return host.strip("[]") or "127.0.0.1", int(port)
