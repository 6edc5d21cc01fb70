"""Special Functions Commands (guide 6.3): host devices the simulated platform does not have.

Rules: the state chart decides where they are allowed (the head drive needs the CAN bus). Camera, audio and the
head drive's velocity are accepted, logged and without effect (reported ``ignored``), never faked; the head
drive's position is kept and reported by GET_STATUS (erratum E-TASK-017).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from pltf.reference_server.commands.registry import ACCEPTED, Outcome, handles

if TYPE_CHECKING:
    from pltf.reference_server.platform import Platform


@handles("CMD_SPEAK_TEXT", "CMD_PLAY_SOUND")
def audio(p: Platform, t: Any, now: float) -> Outcome:
    text = t.text if t.NAME == "CMD_SPEAK_TEXT" else t.filename
    return p.ignore(f"{t.NAME} {text!r}: no audio output on the simulated platform")


@handles("CMD_SET_POS_HEAD_DRIVE")
def head_position(p: Platform, t: Any, now: float) -> Outcome:
    # erratum E-TASK-017: the position GET_STATUS reports as head_position (whole degrees, no dynamics)
    p.head_position = t.angle
    p.log(logging.INFO, f"head drive position: {t.angle} deg")
    return ACCEPTED


@handles("CMD_GRAB_IMAGE", "CMD_SET_POS_PAN_TILT_CAMERA", "CMD_SET_VEL_HEAD_DRIVE")
def absent_device(p: Platform, t: Any, now: float) -> Outcome:
    device = "head drive" if "HEAD" in t.NAME else "camera"
    return p.ignore(f"{t.NAME}: no {device} mounted")
