"""Request Status Commands (guide 6.3, 6.4): the status and position replies."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from pltf.reference_server import status
from pltf.reference_server.commands.registry import Outcome, handles

if TYPE_CHECKING:
    from pltf.reference_server.platform import Platform


@handles("CMD_GET_STATUS")
def get_status(p: Platform, t: Any, now: float) -> Outcome:
    reply, frame = status.status_frame(p, now)
    return Outcome(reply=reply, frame=frame)


@handles("CMD_GET_POSITION")
def get_position(p: Platform, t: Any, now: float) -> Outcome:
    return Outcome(reply=status.position_reply(p))
