"""Ending a tool's Ray actors (the fuzz campaign's workers, the fleet's shards): the one place both do it.

Rules: every actor is asked to end, even when one of them is gone already (its node removed, the cluster shut
down): a gone actor is nothing more to end, never an error of the tool's close.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any


def kill_actors(ray: Any, actors: Iterable[Any]) -> None:
    """``ray.kill`` each actor of ``actors`` (``ray``: the imported ray module, which the tools import lazily)."""
    for actor in actors:
        try:
            ray.kill(actor)
        except Exception:  # an actor already gone: nothing more to end
            continue
