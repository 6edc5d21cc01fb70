"""Which platforms the gateway may connect to (issue 33): a page names its target, the gateway decides.

Rules:
- Allowed: ``--target``, the addresses of Network.ini (guide 5.2: "extend the file ... Network.ini with the
  missing server"; read at each request, so an address the user adds there is allowed at once) and those given
  with ``--allow-target``; every address with ``--allow-any-target``.
- Addresses are compared as (host in lower case, port): ``[::1]:10000`` and ``::1:10000`` are one address;
  ``localhost`` and ``127.0.0.1`` are two (no name is resolved: resolving would be a connection of its own).
- A refused target is refused before any connection attempt, in words that say nothing about the address but
  that it is not on the list (a page must not learn from the gateway which ports of the network are open).
- Adding an address from the page (Open Socket At, ``POST /api/targets``) needs ``--allow-any-target``: else a
  page could put any address on the list and connect to it.
"""

from __future__ import annotations

from dataclasses import dataclass

from pltf.gui.link import parse_target
from pltf.gui.network_ini import NetworkIni


def address(target: str) -> tuple[str, int]:
    host, port = parse_target(target)
    return host.lower().rstrip("."), port


@dataclass(frozen=True)
class TargetList:
    default: str
    ini: NetworkIni
    allowed: frozenset[str] = frozenset()
    any_target: bool = False

    def refusal(self, target: str) -> str | None:
        """None when the gateway may connect to ``target``, else why not (one line, the flags that allow it)."""
        if self.any_target:
            return None
        wanted = address(target)
        known = {address(t) for t in (self.default, *self.allowed)}
        if wanted in known or any(address(t) == wanted for t in self.ini.targets()):
            return None
        return (
            f"{target} is not on this GUI's list of platforms: start `pltf gui` with --allow-target {target} "
            f"(or --allow-any-target), or add it to {self.ini.path}"
        )
