"""Who may come in: the gateway's checks on every HTTP request and WebSocket (issue 33; docs/security.md).

Rules (Jupyter's answer to the same three problems):
- **Host**: a request is served only when its Host header names the address the gateway listens on,
  ``localhost``, a loopback address, or a name given with ``--allow-host``; under a wildcard listen (0.0.0.0,
  ::) any IP address is the gateway's own. Anything else (a DNS-rebinding page: its name resolves to us) gets
  403 naming ``--allow-host``.
- **Origin**: a browser's Origin must name an allowed host too (never compared with the Host header, which the
  rebinding page controls as well); for an address of this machine its port must be the gateway's own port (a
  page served by another local program is another origin); an ``--allow-host`` name may come through a proxy, on
  any port. A request without an Origin is not a page's and passes on to the token.
- **Token**: with a token set (``--listen`` beyond loopback, or ``--token``) every request must carry it: in the
  query (``?token=``), an ``Authorization: token T`` header, or the cookie the gateway sets after the first
  visit (HttpOnly, SameSite=Strict, named with the gateway's port: two gateways on one machine keep theirs).
  Compared with ``hmac.compare_digest``. Loopback clients are no exception: behind a local reverse proxy every
  client looks local.
- Each refusal is one line that says why and which flag allows it; nothing past the door runs. The gateway's log
  says each distinct refusal once (a page that keeps knocking does not fill it).
"""

from __future__ import annotations

import hashlib
import hmac
import ipaddress
import logging
import secrets
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from urllib.parse import urlsplit

from aiohttp import web
from aiohttp.typedefs import Middleware

log = logging.getLogger("pltf.gui")
LOGGED_AT_MOST = 100  # distinct refusals written to the log
COOKIE = "pltf_gui_token"  # + the gateway's port: browsers keep one cookie jar per host, whatever the port
WILDCARDS = frozenset({"", "0.0.0.0", "::"})
Handler = Callable[[web.Request], Awaitable[web.StreamResponse]]


def new_token() -> str:
    return secrets.token_hex(24)


def is_loopback(host: str) -> bool:
    """``localhost`` or a loopback IP address (127.0.0.0/8, ::1)."""
    host = host.strip("[]").lower().rstrip(".")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def split_host(text: str) -> tuple[str, int | None]:
    """A Host header or an origin's netloc -> (lower-case host without brackets, port or None)."""
    text = text.strip().lower()
    if text.startswith("["):
        host, _, rest = text[1:].partition("]")
        port = rest[1:] if rest.startswith(":") else ""
    else:
        host, sep, port = text.rpartition(":")
        if not sep or ":" in host:  # no port, or a bare IPv6 address
            host, port = text, ""
    return host.rstrip("."), int(port) if port.isdigit() else None


def _is_ip(host: str) -> bool:
    try:
        ipaddress.ip_address(host)
    except ValueError:
        return False
    return True


@dataclass(frozen=True)
class Doors:
    """The gateway's checks, from the command line (``pltf gui --help``)."""

    listen_host: str = "127.0.0.1"
    allow_hosts: frozenset[str] = frozenset()
    token: str | None = None
    _cookie: str = field(init=False, repr=False, default="")
    _logged: set[str] = field(init=False, repr=False, default_factory=set, compare=False)

    def __post_init__(self) -> None:
        hosts = frozenset(h.strip("[]").lower().rstrip(".") for h in self.allow_hosts)
        object.__setattr__(self, "allow_hosts", hosts)
        if self.token is not None:  # the cookie holds a value derived from the token, not the token itself
            digest = hmac.new(self.token.encode(), b"pltf gui cookie", hashlib.sha256).hexdigest()
            object.__setattr__(self, "_cookie", digest)

    @property
    def wildcard(self) -> bool:
        return self.listen_host.strip("[]") in WILDCARDS

    def own(self, host: str) -> bool:
        """A name or address of this gateway itself: loopback, the listen address, any IP under a wildcard."""
        return is_loopback(host) or host == self.listen_host.strip("[]").lower() or (self.wildcard and _is_ip(host))

    def host_refusal(self, header: str | None) -> str | None:
        host, _ = split_host(header or "")
        if host and (self.own(host) or host in self.allow_hosts):
            return None
        shown = header if header else "(none)"
        return (
            f"Host {shown!r} is not one of this GUI's names: it answers for the address it listens on, localhost "
            f"and loopback addresses; start `pltf gui` with --allow-host {host or 'NAME'} to allow that name"
        )

    def origin_refusal(self, origin: str | None, own_port: int) -> str | None:
        if origin is None:
            return None  # not a page's request (curl, a script): the token, if any, decides
        parts = urlsplit(origin)
        host, port = split_host(parts.netloc)
        port = port if port is not None else {"http": 80, "https": 443}.get(parts.scheme)
        if host in self.allow_hosts or (host and self.own(host) and port == own_port):
            return None
        return (
            f"request from the page at {origin!r} refused: it is not this GUI's page; start `pltf gui` with "
            f"--allow-host {host or 'NAME'} if that page may drive the platform"
        )

    def token_ok(self, request: web.Request, own_port: int) -> bool:
        if self.token is None:
            return True
        given = request.query.get("token")
        if given is None:
            scheme, _, value = request.headers.get("Authorization", "").partition(" ")
            given = value.strip() if scheme.lower() == "token" else None
        if given is not None:
            return hmac.compare_digest(given.encode(), self.token.encode())
        return hmac.compare_digest(request.cookies.get(f"{COOKIE}_{own_port}", "").encode(), self._cookie.encode())

    def _say_once(self, why: str) -> None:
        if why not in self._logged and len(self._logged) < LOGGED_AT_MOST:
            self._logged.add(why)
            log.warning("%s", why)

    def middleware(self) -> Middleware:
        @web.middleware
        async def doors(request: web.Request, handler: Handler) -> web.StreamResponse:
            sockname = request.transport.get_extra_info("sockname") if request.transport else None
            own_port = int(sockname[1]) if sockname else -1
            why = self.host_refusal(request.headers.get("Host"))
            if why is None:
                why = self.origin_refusal(request.headers.get("Origin"), own_port)
            if why is not None:
                self._say_once(why)
                raise web.HTTPForbidden(text=why + "\n")
            if not self.token_ok(request, own_port):
                self._say_once(f"refused a request without the token from {request.remote or 'an unknown address'}")
                raise web.HTTPUnauthorized(
                    text="this GUI needs its token: open the URL `pltf gui` printed (…/?token=…), "
                    "or send `Authorization: token TOKEN`\n"
                )
            response = await handler(request)
            if self.token is not None and "token" in request.query and not response.prepared:
                cookie = f"{COOKIE}_{own_port}"
                response.set_cookie(cookie, self._cookie, httponly=True, samesite="Strict", path="/")
            return response

        return doors
