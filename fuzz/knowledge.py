"""What the fuzzer has learnt from the target's replies, fed back into later telegrams.

Rules: ``learn(reply)`` takes any decoded reply telegram; nothing here does I/O. Every list is bounded so a
hostile target cannot make the fuzzer grow without limit.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from pltf.spec.telegram import Telegram

MAX_ITEMS = 256
_LEARNT = frozenset(
    (
        "CMD_GET_STATUS",
        "CMD_GET_PLTF_PARAM_VEC",
        "CMD_GET_PLTF_PARAM",
        "CMD_GET_ROADMAP",
        "CMD_GET_MAP",
        "CMD_GET_PROGRAM",
    )
)
LIGHT = ("param_keys", "param_values", "stations", "pose", "operation_state", "motion_mode")
_STATION = re.compile(rb'<station\b[^>]*\bname="([^"]{1,64})"')
_STATION_ID = re.compile(rb'<station\b[^>]*\bid="([^"]{1,64})"')


@dataclass
class Knowledge:
    param_keys: list[str] = field(default_factory=list)
    param_values: dict[str, str] = field(default_factory=dict)
    stations: list[str] = field(default_factory=list)
    pose: tuple[int, int, int] = (0, 0, 0)
    operation_state: int | None = None
    motion_mode: int | None = None
    documents: dict[str, bytes] = field(default_factory=dict)  # reply name -> last XML seen
    version: int = 0  # counts the replies learnt from (a copy elsewhere is stale when it differs)

    def light(self) -> dict[str, Any]:
        """Everything but the documents, by field name (``update`` takes it, or any part of it, back)."""
        return {name: getattr(self, name) for name in LIGHT}

    def update(self, light: dict[str, Any], documents: dict[str, bytes]) -> None:
        """Take over what another copy learnt: the fields of ``light()`` that changed and the documents that
        changed."""
        for name, value in light.items():
            setattr(self, name, value)
        self.documents.update(documents)
        self.version += 1

    def learn(self, reply: Telegram) -> None:
        name = reply.NAME
        if name in _LEARNT:
            self.version += 1
        if name == "CMD_GET_STATUS":
            self.pose = (reply.est_x, reply.est_y, reply.est_angle)  # type: ignore[attr-defined]
            self.operation_state = reply.operation_state  # type: ignore[attr-defined]
            self.motion_mode = reply.motion_mode  # type: ignore[attr-defined]
        elif name == "CMD_GET_PLTF_PARAM_VEC":
            for entry in reply.parameters[:MAX_ITEMS]:  # type: ignore[attr-defined]
                self._add_param(entry.key, entry.value)
        elif name == "CMD_GET_PLTF_PARAM":
            if reply.key:  # type: ignore[attr-defined]
                self._add_param(reply.key, reply.value)  # type: ignore[attr-defined]
        elif name in ("CMD_GET_ROADMAP", "CMD_GET_MAP", "CMD_GET_PROGRAM"):
            xml = reply.xml.encode("latin-1")  # type: ignore[attr-defined]
            if xml:
                self.documents[name] = xml[: 1 << 20]
            if name == "CMD_GET_ROADMAP":
                names = [m.decode("latin-1") for m in _STATION.findall(xml)]
                names += [m.decode("latin-1") for m in _STATION_ID.findall(xml)]
                for n in names:
                    if n not in self.stations and len(self.stations) < MAX_ITEMS:
                        self.stations.append(n)

    def _add_param(self, key: str, value: str) -> None:
        if key not in self.param_values and len(self.param_keys) < MAX_ITEMS:
            self.param_keys.append(key)
        if key in self.param_values or len(self.param_values) < MAX_ITEMS:
            self.param_values[key] = value[:256]
