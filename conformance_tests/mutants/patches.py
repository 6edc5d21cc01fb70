"""Model mutants: each function breaks one rule of the reference server's platform model by monkeypatching it
in the server's own process (serve.py calls it before the server starts). reference_server/ is never edited.

Rules: a patch changes the smallest thing that breaks its requirement - one entry of the state chart table,
one method - so the mutant differs from the reference server in exactly that behaviour.
"""

from __future__ import annotations

import os
from typing import Any


def set_mode_anywhere() -> None:
    from pltf.reference_server import state_chart as sc

    sc.RULES["CMD_SET_MODE"] = sc.Rule(frozenset({sc.State.READY, sc.State.RUNNING, sc.State.BREAKED}))


def start_when_connected() -> None:
    from pltf.reference_server import state_chart as sc

    sc.RULES["CMD_START"] = sc.Rule(frozenset({sc.State.READY, sc.State.CONNECTED}), sc.State.RUNNING)


def break_no_transition() -> None:
    from pltf.reference_server import state_chart as sc

    sc.RULES["CMD_BREAK"] = sc.Rule(sc.RULES["CMD_BREAK"].allowed, None)


def shutdown_no_transition() -> None:
    from pltf.reference_server import state_chart as sc

    sc.RULES["CMD_SHUTDOWN_PLTF"] = sc.Rule(sc.RULES["CMD_SHUTDOWN_PLTF"].allowed, None)


def parameter_range_unchecked() -> None:
    from pltf.spec import parameters

    parameters.Parameter._in_range = lambda self, value: value  # type: ignore[method-assign]
    original = parameters.Parameter.format
    parameters.Parameter.format = lambda self, value: (  # type: ignore[method-assign]
        original(self, value)
        if self.minimum <= value <= self.maximum
        else repr(value)
        if isinstance(value, float)
        else str(value)
    )


def documents_unvalidated() -> None:
    from lxml import etree

    from pltf.reference_server import documents

    def parse_only(kind: Any, data: bytes) -> Any:
        from pltf.spec.documents import DocumentError

        try:
            return etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True)).getroottree()
        except etree.XMLSyntaxError as exc:
            raise DocumentError(str(exc)) from None

    documents.validate_document = parse_only  # type: ignore[assignment]


def refusal_clears_active() -> None:
    from pltf.reference_server import documents

    original = documents.Documents.set

    def set_(self: Any, kind: Any, name: str, data: bytes) -> Any:
        self._active.pop(kind, None)
        return original(self, kind, name, data)

    documents.Documents.set = set_  # type: ignore[method-assign]


def save_does_nothing() -> None:
    from pltf.reference_server import documents

    documents.Documents.save = lambda self, kind: self.storage.path(kind)  # type: ignore[method-assign]


def stop_keeps_command() -> None:
    from pltf.reference_server import kinematics
    from pltf.reference_server.world import world

    # both motion models of the server (pltf serve --motion ideal / world)
    kinematics.Drive.stop = lambda self: None  # type: ignore[method-assign]
    world.World.stop = lambda self: None  # type: ignore[method-assign]


def no_watchdog() -> None:
    from pltf.reference_server import platform

    original = platform.Platform.__init__

    def init(self: Any, *args: Any, **kwargs: Any) -> None:
        original(self, *args, **kwargs)
        params = self.drive.params
        self.drive.params = lambda name: 10**9 if name == "VelWatchdogTime" else params(name)

    platform.Platform.__init__ = init  # type: ignore[method-assign]


def moves_in_every_mode() -> None:
    from pltf.reference_server import platform

    platform.Platform.unless_mode = lambda self, name, *modes: None  # type: ignore[method-assign]


def die_on_malformed() -> None:
    from pltf.reference_server import network
    from pltf.spec.codec import TelegramDecoder
    from pltf.spec.errors import RemoteProtocolError

    class Dying(TelegramDecoder):
        def next_telegram(self) -> Any:
            try:
                return super().next_telegram()
            except RemoteProtocolError:
                os._exit(3)

    network.TelegramDecoder = Dying  # type: ignore[misc]


def allow_in_state(command: str, state: str) -> None:
    """``command`` is also accepted in ``state`` (a state chart cell flipped); its rule's target stays."""
    from pltf.reference_server import state_chart as sc

    rule = sc.RULES[command]
    extra = next(s for s in sc.State if s.name.lower().replace("_", "-") == state)
    sc.RULES[command] = sc.Rule(rule.allowed | {extra}, rule.target, rule.blocked_by_emergency)


def parameter_text_lenient() -> None:
    """Any number text is taken (fractions truncated, commas as points) and any word but true is false."""
    from pltf.spec import parameters

    def integer(text: str) -> int:
        return int(float(text.replace(",", ".") or 0))

    def double(text: str) -> float:
        return float(text.replace(",", ".") or 0)

    def boolean(text: str) -> bool:
        return text.strip().lower() == "true"

    parameters._PARSERS = {
        parameters.DataType.BOOLEAN: boolean,
        parameters.DataType.INTEGER: integer,  # type: ignore[attr-defined]
        parameters.DataType.DOUBLE: double,
    }


PATCHES = {
    name: fn
    for name, fn in globals().items()
    if callable(fn) and not name.startswith("_") and fn.__module__ == __name__
}
