"""The well-known schemas of the MCAP export (proxy/mcap_export.py): JSON schemas for JSON-encoded messages, and
foxglove.LaserScan's as protobuf (a FileDescriptorSet, mcap_proto.py: a status's 541 ranges as packed doubles).

Foxglove's schemas (foxglove.PoseInFrame, FrameTransform, LaserScan, SceneUpdate, Log) are written out here from
their published JSON-schema definitions (github foxglove/schemas, schemas/jsonschema/*.json), the parts a viewer
needs: Foxglove, Lichtblick and the ROS 2 tools recognise a channel by the schema's name and read its JSON by the
field names below. ``pltf.Telegram``, the raw channel's, is this toolkit's own.

Units: Foxglove's are metres and radians; the protocol's are mm (guide 6.4), so positions are divided by 1000.
"""

from __future__ import annotations

import json
from typing import Any

from pltf.proxy import mcap_proto

ENCODING = "jsonschema"  # the JSON schemas' encoding; their messages' is "json"
PROTOBUF_SCHEMAS = {"foxglove.LaserScan": mcap_proto.file_descriptor_set}  # name: its FileDescriptorSet

_NUMBER: dict[str, Any] = {"type": "number"}
TIME: dict[str, Any] = {
    "type": "object",
    "title": "time",
    "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999},
    },
}
DURATION: dict[str, Any] = {
    "type": "object",
    "title": "duration",
    "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}},
}
VECTOR3: dict[str, Any] = {
    "title": "foxglove.Vector3",
    "type": "object",
    "properties": {"x": _NUMBER, "y": _NUMBER, "z": _NUMBER},
}
QUATERNION: dict[str, Any] = {
    "title": "foxglove.Quaternion",
    "type": "object",
    "properties": {"x": _NUMBER, "y": _NUMBER, "z": _NUMBER, "w": _NUMBER},
}
POSE: dict[str, Any] = {
    "title": "foxglove.Pose",
    "type": "object",
    "properties": {"position": VECTOR3, "orientation": QUATERNION},
}
COLOR: dict[str, Any] = {
    "title": "foxglove.Color",
    "type": "object",
    "properties": {"r": _NUMBER, "g": _NUMBER, "b": _NUMBER, "a": _NUMBER},
}


def _array(item: dict[str, Any]) -> dict[str, Any]:
    return {"type": "array", "items": item}


def _schema(title: str, description: str, properties: dict[str, Any]) -> dict[str, Any]:
    return {"title": title, "description": description, "type": "object", "properties": properties}


POSE_IN_FRAME = _schema(
    "foxglove.PoseInFrame",
    "A timestamped pose for an object or reference frame in 3D space",
    {"timestamp": TIME, "frame_id": {"type": "string"}, "pose": POSE},
)
FRAME_TRANSFORM = _schema(
    "foxglove.FrameTransform",
    "A transform between two reference frames in 3D space",
    {
        "timestamp": TIME,
        "parent_frame_id": {"type": "string"},
        "child_frame_id": {"type": "string"},
        "translation": VECTOR3,
        "rotation": QUATERNION,
    },
)
LINE_PRIMITIVE: dict[str, Any] = {
    "title": "foxglove.LinePrimitive",
    "type": "object",
    "properties": {
        "type": {
            "title": "foxglove.LineType",
            "oneOf": [{"title": t, "const": i} for i, t in enumerate(("LINE_STRIP", "LINE_LOOP", "LINE_LIST"))],
        },
        "pose": POSE,
        "thickness": _NUMBER,
        "scale_invariant": {"type": "boolean"},
        "points": _array(VECTOR3 | {"title": "foxglove.Point3"}),
        "color": COLOR,
        "colors": _array(COLOR),
        "indices": _array({"type": "integer", "minimum": 0}),
    },
}
TEXT_PRIMITIVE: dict[str, Any] = {
    "title": "foxglove.TextPrimitive",
    "type": "object",
    "properties": {
        "pose": POSE,
        "billboard": {"type": "boolean"},
        "font_size": _NUMBER,
        "scale_invariant": {"type": "boolean"},
        "color": COLOR,
        "text": {"type": "string"},
    },
}
SCENE_ENTITY: dict[str, Any] = {
    "title": "foxglove.SceneEntity",
    "type": "object",
    "properties": {
        "timestamp": TIME,
        "frame_id": {"type": "string"},
        "id": {"type": "string"},
        "lifetime": DURATION,
        "frame_locked": {"type": "boolean"},
        "metadata": _array(
            {
                "title": "foxglove.KeyValuePair",
                "type": "object",
                "properties": {"key": {"type": "string"}, "value": {"type": "string"}},
            }
        ),
        **{k: _array({"type": "object"}) for k in ("arrows", "cubes", "spheres", "cylinders", "triangles", "models")},
        "lines": _array(LINE_PRIMITIVE),
        "texts": _array(TEXT_PRIMITIVE),
    },
}
SCENE_UPDATE = _schema(
    "foxglove.SceneUpdate",
    "An update to the entities displayed in a 3D scene",
    {
        "deletions": _array(
            {
                "title": "foxglove.SceneEntityDeletion",
                "type": "object",
                "properties": {"timestamp": TIME, "type": {"type": "integer"}, "id": {"type": "string"}},
            }
        ),
        "entities": _array(SCENE_ENTITY),
    },
)
LOG_LEVELS = ("UNKNOWN", "DEBUG", "INFO", "WARNING", "ERROR", "FATAL")
LOG = _schema(
    "foxglove.Log",
    "A log message",
    {
        "timestamp": TIME,
        "level": {"title": "foxglove.LogLevel", "oneOf": [{"title": t, "const": i} for i, t in enumerate(LOG_LEVELS)]},
        "message": {"type": "string"},
        "name": {"type": "string"},
        "file": {"type": "string"},
        "line": {"type": "integer", "minimum": 0},
    },
)
TELEGRAM = _schema(
    "pltf.Telegram",
    "One frame of a pltf proxy recording as it passed (guide 6.2), or bytes marked malformed",
    {
        "timestamp": TIME,
        "conn": {"type": "integer", "description": "connection number, from 1, in the proxy's order"},
        "port": {"type": "integer", "description": "the target's port (10000, 10002)"},
        "direction": {"enum": ["request", "reply"], "description": "request: client to platform"},
        "kind": {"enum": ["frame", "raw"], "description": "raw: bytes after a framing error"},
        "name": {"type": "string", "description": "the telegram's name, or malformed"},
        "hex": {"type": "string", "description": "the bytes as they passed"},
        "error": {"type": ["string", "null"], "description": "<codec error class>: reason, when malformed"},
    },
)
SCHEMAS = {s["title"]: s for s in (POSE_IN_FRAME, FRAME_TRANSFORM, SCENE_UPDATE, LOG, TELEGRAM)}


def schema_encoding(name: str) -> str:
    """The encoding of the schema ``name`` as the export writes it: protobuf or jsonschema."""
    return mcap_proto.ENCODING if name in PROTOBUF_SCHEMAS else ENCODING


def schema_bytes(name: str) -> bytes:
    if name in PROTOBUF_SCHEMAS:
        return PROTOBUF_SCHEMAS[name]()
    return json.dumps(SCHEMAS[name], separators=(",", ":")).encode()
