"""The spec's enums the server model uses, typed ``Any``: they are built at import from spec/enums.yaml, so their
members are invisible to mypy."""

from __future__ import annotations

from typing import Any

from pltf.spec.model import enum_classes

_E: dict[str, Any] = dict(enum_classes())
MotionMode: Any = _E["MotionMode"]
PlannerState: Any = _E["PlannerState"]
MouseButton: Any = _E["MouseButton"]
Event: Any = _E["Event"]
AppError: Any = _E["AppError"]
