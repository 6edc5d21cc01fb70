"""Where <moveto> finds its entity (E-TASK-008), from what both facades can observe.

Rules: the tracked person, ball and moving object are the clusters of CMD_GET_DEBUG_DATA (map coordinates,
E-TASK-008), the nearest one to the platform wins; the charging station is the roadmap station whose name or
id starts with "charg" (case-insensitive; the fixtures' "Charging"), docked at its own frame. Pure functions:
the local and the remote facade call them on the same data, so both drive to the same frame.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

from reference_server.tasks.facade import Pose, Target

CHARGING_PREFIX = "charg"


def nearest_cluster(clusters: Iterable[tuple[int, int, int]], pose: Pose) -> Target | None:
    """The (x, y, index) cluster nearest the platform, as a point target; None when there is none."""
    best = min(clusters, key=lambda c: math.hypot(c[0] - pose.x, c[1] - pose.y), default=None)
    return None if best is None else Target(float(best[0]), float(best[1]), None)


def charging_station(roadmap_root: Any) -> Target | None:
    """The charging station of a validated roadmap (lxml element or tree), or None."""
    if roadmap_root is None:
        return None
    root = roadmap_root.getroot() if hasattr(roadmap_root, "getroot") else roadmap_root
    for st in root.iterfind("stations/station"):
        names = (st.get("name") or "", st.get("id") or "")
        if any(n.lower().startswith(CHARGING_PREFIX) for n in names):
            pt = st.find("point")
            return Target(float(pt.get("x")), float(pt.get("y")), float(st.get("angle") or 0))
    return None
