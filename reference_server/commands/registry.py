"""The handler table of the platform model and what a handler returns.

Rules:
- One table, ``HANDLERS``: telegram name -> ``handler(platform, telegram, now) -> Outcome``. A module of
  reference_server/commands/ registers its handlers with ``@handles(...)`` at import; a name registered twice
  is a bug (``handles`` raises), so a replacement must say so with ``replace=True``.
- ``Platform.handle`` calls a handler only after the state chart allowed the command, and fires the chart's
  transition after it unless the outcome is ``refused``, ``failed`` or ``pending`` (the transition then follows
  when the hardware finished, e.g. the self test of CMD_INIT_PLTF; ``Platform.awaiting`` names the command).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from pltf.spec.telegram import Telegram

if TYPE_CHECKING:
    from pltf.reference_server.platform import Platform


@dataclass(frozen=True)
class Outcome:
    """What the network shell must do after a telegram (``refused``/``ignored``/``pending`` explain it)."""

    reply: Telegram | None = None
    frame: bytes | None = None  # ``reply`` encoded already (the status, from its per-epoch cache), or None
    close_connection: bool = False
    exit_server: bool = False
    refused: str | None = None  # not allowed now, or invalid: nothing changed
    ignored: str | None = None  # allowed, but without effect (motion mode, absent hardware, unused command)
    pending: str | None = None  # accepted; the state transition follows when the hardware is done
    failed: str | None = None  # carried out, but the hardware reported a failure: no state transition


ACCEPTED = Outcome()
# The spec's telegram classes are built at import: their fields are invisible to mypy, so handlers take Any.
Handler = Callable[["Platform", Any, float], Outcome]
HANDLERS: dict[str, Handler] = {}


def handles(*names: str, replace: bool = False) -> Callable[[Handler], Handler]:
    def register(func: Handler) -> Handler:
        for name in names:
            if name in HANDLERS and not replace:
                raise ValueError(f"{name} already has a handler ({HANDLERS[name].__module__})")
            HANDLERS[name] = func
        return func

    return register


def handler_names() -> frozenset[str]:
    return frozenset(HANDLERS)
