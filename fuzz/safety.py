"""What the fuzzer never sends, and what it sends only with ``--allow-motion``.

Rules: one table per policy, each id with its reason. A case is dropped (not repaired) when any plausible
reader of its bytes could see a forbidden id (``pltf.fuzz.wire.forbidden_ids``): a lenient or resynchronising
server must not be able to find one either.
"""

from __future__ import annotations

from pltf.spec.codec import REQUESTS

# Telegrams that end the target on purpose: its death would be the protocol working, not a finding.
NEVER: dict[int, str] = {
    REQUESTS.CMD_EXIT.ID: "guide 6.3 CMD_EXIT: 'Shut the platform down' - ends the program on purpose",
    REQUESTS.CMD_SHUTDOWN_HOST.ID: "field evidence: shuts the host computer down",
}

# Telegrams that make a real platform move (or release what holds it): only with --allow-motion.
MOTION: dict[int, str] = {
    REQUESTS.CMD_START.ID: "guide 4.2: the only way into Running, where motion happens",
    REQUESTS.CMD_CONTINUE.ID: "guide 6.3: back to Running after a break",
    REQUESTS.CMD_SET_BRAKE.ID: "releases the drive brakes",
    **{
        REQUESTS[name].ID: "a motion command: a server that ignores the state chart would move"
        for name in (
            "CMD_MOVE_PATH",
            "CMD_MOVE_TO_STATION",
            "CMD_MOVE_ABS",
            "CMD_MOVE_REL",
            "CMD_MOVE_VEL_WHEEL",
            "CMD_MOVE_VEL",
        )
    },
    REQUESTS.CMD_SEND_CAN_MESSAGE.ID: "raw CAN frames can command the motor controllers",
    REQUESTS.CMD_SET_POS_HEAD_DRIVE.ID: "moves the head drive",
    REQUESTS.CMD_SET_VEL_HEAD_DRIVE.ID: "moves the head drive",
    REQUESTS.CMD_SET_POS_PAN_TILT_CAMERA.ID: "moves the camera",
    REQUESTS.CMD_SET_EVENT.ID: "starts a post-process replay (recorded motion)",
    REQUESTS.CMD_STOP_MOTIONTHREAD.ID: "field evidence: stops the motion thread (layout unknown)",
    REQUESTS.CMD_RESTART_MOTIONTHREAD.ID: "field evidence: restarts the motion thread (layout unknown)",
}


def forbidden(allow_motion: bool) -> frozenset[int]:
    ids = set(NEVER)
    if not allow_motion:
        ids |= set(MOTION)
    return frozenset(ids)
