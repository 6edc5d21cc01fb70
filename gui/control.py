"""Viewers and one driver (issue 33): who may send the telegrams that move or change the platform.

Rules:
- Guide 4.2: "For each port one client is able to connect": the guide's GUI is the one client of its port, so of
  the tabs that share the gateway's connection to a target one at a time holds control; the others watch.
- A command is every request the platform does not answer: guide 6.1 "The platform returns data only on
  request", so the answered requests (``reply`` in spec/telegrams.yaml) are the ones that read and everything else
  commands (moves, modes, outputs, documents, parameters, CAN, sounds, CMD_EXIT). Derived from the spec, not a
  second list (erratum E-GUI-006).
- Nobody holds control at first; the first tab to send a command takes it, and keeps it until it leaves or
  another tab takes it by an explicit action (``take``). A viewer's command is refused, never sent (erratum
  E-GUI-007).
- ``read_only``: nobody holds control and every command is refused; reads are served as before.
Sans-IO: tabs are any hashable, labels are text; the caller tells the tabs (``view``).
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass, field
from typing import Any

from pltf.spec.model import load_telegrams

# guide 6.1: requests without a reply are commands; identifier -> name
COMMANDS: dict[int, str] = {t.id: t.name for t in load_telegrams() if not t.answered}


@dataclass
class Control:
    read_only: bool = False
    holder: Hashable | None = None
    labels: dict[Hashable, str] = field(default_factory=dict)

    def join(self, tab: Hashable, label: str) -> None:
        self.labels[tab] = label

    def leave(self, tab: Hashable) -> bool:
        """The tab has gone; True when it held control (now free)."""
        self.labels.pop(tab, None)
        if self.holder == tab:
            self.holder = None
            return True
        return False

    def refusal(self, tab: Hashable) -> tuple[str, str] | None:
        """(reason, message) when ``tab`` may not command now, else None."""
        if self.read_only:
            return "read_only", "refused: this GUI is read-only (pltf gui --read-only): it sends no command"
        if self.holder is not None and self.holder != tab:
            return "viewer", f"refused: {self.labels.get(self.holder, 'another tab')} drives; take control first"
        return None

    def claim(self, tab: Hashable) -> bool:
        """A command of ``tab`` went out: it holds control if nobody did. True when the holder changed."""
        if self.holder is None and not self.read_only:
            self.holder = tab
            return True
        return False

    def take(self, tab: Hashable) -> bool:
        """The explicit "Take control"; True when the holder changed (never in read-only)."""
        if self.read_only or self.holder == tab:
            return False
        self.holder = tab
        return True

    def view(self, tab: Hashable) -> dict[str, Any]:
        """What ``tab`` is told: ``{"event": "control", "holder", "you", "read_only", "message"}``."""
        holder = self.labels.get(self.holder) if self.holder is not None else None
        if self.read_only:
            message = "read-only: this GUI sends no command"
        elif self.holder is None:
            message = "nobody drives: the first command takes control"
        elif self.holder == tab:
            message = f"you drive ({holder})"
        else:
            message = f"{holder} drives; you watch"
        return {
            "event": "control",
            "holder": holder,
            "you": self.holder == tab and self.holder is not None,
            "read_only": self.read_only,
            "message": message,
        }
