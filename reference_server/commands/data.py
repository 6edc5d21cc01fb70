"""Platform Data Commands (guide 6.3): documents (map, roadmap, program), mapping, the pose, parameters.

Rules: every document is validated before it becomes active (reference_server.documents); a refused one
leaves the active one in place. A parameter is type- and range-checked as a whole (erratum E-PAR-007).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from pltf.reference_server import status
from pltf.reference_server.commands.motion import rad
from pltf.reference_server.commands.registry import ACCEPTED, Outcome, handles
from pltf.reference_server.documents import from_wire, to_wire
from pltf.reference_server.kinematics import Frame
from pltf.reference_server.storage import StorageError
from pltf.spec.documents import DocumentError, DocumentKind
from pltf.spec.parameters import ParameterError

if TYPE_CHECKING:
    from pltf.reference_server.platform import Platform

DOCUMENT_OF = {"MAP": DocumentKind.MAP, "ROADMAP": DocumentKind.ROADMAP, "PROGRAM": DocumentKind.PROGRAM}


def _kind(t: Any) -> DocumentKind:
    return DOCUMENT_OF[t.NAME.split("_", 2)[2]]


@handles("CMD_SET_MAP", "CMD_SET_ROADMAP", "CMD_SET_PROGRAM")
def set_document(p: Platform, t: Any, now: float) -> Outcome:
    kind = _kind(t)
    name = getattr(t, "name", "")
    try:
        p.documents.set(kind, name, from_wire(t.xml))
    except DocumentError as exc:
        return p.refuse(f"set {kind.value} {name!r} refused: {exc}")
    p.activated(kind)
    p.log(logging.INFO, f"set {kind.value}: {name} ({len(t.xml)} bytes)")
    return ACCEPTED


@handles("CMD_GET_MAP", "CMD_GET_ROADMAP", "CMD_GET_PROGRAM")
def get_document(p: Platform, t: Any, now: float) -> Outcome:
    doc = p.documents.get(_kind(t))
    xml, name = ("", "") if doc is None else (to_wire(doc.data), doc.name)
    fields = {"xml": xml} if t.NAME == "CMD_GET_PROGRAM" else {"xml": xml, "name": name}
    return Outcome(reply=status.reply(t.NAME, **fields))


@handles("CMD_LOAD_MAP", "CMD_LOAD_ROADMAP", "CMD_LOAD_PROGRAM")
def load_document(p: Platform, t: Any, now: float) -> Outcome:
    return p.load_document(_kind(t))


@handles("CMD_SAVE_MAP", "CMD_SAVE_ROADMAP", "CMD_SAVE_PROGRAM")
def save_document(p: Platform, t: Any, now: float) -> Outcome:
    kind = _kind(t)
    try:
        path = p.documents.save(kind)
    except StorageError as exc:
        return p.refuse(f"save {kind.value} refused: {exc}")
    p.log(logging.INFO, f"save {kind.value}: {path}")
    return ACCEPTED


@handles("CMD_MAPPING_START", "CMD_MAPPING_STOP", "CMD_MAPPING_RESET")
def mapping(p: Platform, t: Any, now: float) -> Outcome:
    if t.NAME != "CMD_MAPPING_RESET":
        p.mapping = t.NAME == "CMD_MAPPING_START"
    what = "reset" if t.NAME == "CMD_MAPPING_RESET" else ("on" if p.mapping else "off")
    p.log(logging.INFO, f"mapping mode {what} (nothing is mapped yet)")
    return ACCEPTED


@handles("CMD_SET_FRM_PLTF")
def set_frame(p: Platform, t: Any, now: float) -> Outcome:
    # guide 6.3: "Set the estimated frame of the platform": the estimate, not the body (erratum E-HW-023)
    p.motion.set_pose(Frame(t.x, t.y, rad(t.angle)))
    p.log(logging.INFO, f"estimated frame set to x:{t.x} y:{t.y} a:{p.motion.pose.angle:.3f}")
    return ACCEPTED


@handles("CMD_SET_PLTF_PARAM")
def set_param(p: Platform, t: Any, now: float) -> Outcome:
    try:
        p.params.set_text(t.key, t.value)
    except ParameterError as exc:  # erratum E-PAR-007: refused as a whole, the old value stays
        return p.refuse(f"set parameter refused: {exc}")
    p.log(logging.INFO, f"parameter {t.key} = {p.params.get_text(t.key)}")
    return ACCEPTED


@handles("CMD_GET_PLTF_PARAM")
def get_param(p: Platform, t: Any, now: float) -> Outcome:
    return Outcome(reply=status.param_reply(p.params, t.key))


@handles("CMD_GET_PLTF_PARAM_VEC")
def get_param_vec(p: Platform, t: Any, now: float) -> Outcome:
    return Outcome(reply=status.param_vec_reply(p.params))
