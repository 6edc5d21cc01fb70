"""Python client library for the Neobotix PlatformCtrl socket protocol (guide chapter 6).

``PlatformClient`` (blocking) and ``AsyncPlatformClient`` (asyncio) have one method per command of the
spec, named after it (``CMD_MOVE_ABS`` -> ``move_abs(x_mm, y_mm, angle_mdeg)``), typed replies for the
GET_* requests (``get_status() -> Status``), waits (``wait_state``, ``wait_mode``, ``wait_target_reached``,
``wait_until``) and one exception family (``PlatformError``). See clients/README.md.

``AsyncPlatformClient`` is imported on first use (PEP 562 ``__getattr__``): asyncio alone costs a blocking
client's process more than the rest of the library (issue 18: ``import pltf.client`` under 100 ms).
"""

from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

from pltf.client._enums import (
    AppError,
    BoardType,
    BrakeState,
    CanBufferMode,
    CanNode,
    EmergencyState,
    Event,
    Flag,
    GraphicColor,
    GraphicType,
    MotionMode,
    MotorIndex,
    MouseButton,
    OperationState,
    OutputLevel,
    ParamCategory,
    ParamDataType,
    PlannerState,
)
from pltf.client._replies import (
    Button,
    Camera,
    CanMessage,
    CanMessages,
    Circle,
    Cluster,
    DebugData,
    DebugFrame,
    Frame,
    GraphicObject,
    Map,
    ObservedLine,
    ParamEntry,
    PltfParam,
    PltfParamVec,
    Point,
    Position,
    Program,
    ProtocolEntry,
    Reply,
    Roadmap,
    ScanPoint,
    Segment,
    Status,
    Variable,
    typed_reply,
)
from pltf.client._reply_extras import Pose, format_param_value, parse_param_value
from pltf.client.core import ClientCore, PendingReply
from pltf.client.errors import (
    CommandRejected,
    ConnectionClosed,
    InvalidArgument,
    PlatformError,
    ProtocolError,
    Timeout,
)
from pltf.client.sync import DEFAULT_PORT, DEFAULT_TIMEOUT, PlatformClient, WireLog

if TYPE_CHECKING:
    from pltf.client.aio import AsyncPlatformClient

# attribute -> the module that defines it, imported when the attribute is first read
_LAZY = {"AsyncPlatformClient": "pltf.client.aio"}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})


__all__ = [
    "DEFAULT_PORT",
    "DEFAULT_TIMEOUT",
    "AppError",
    "AsyncPlatformClient",
    "BoardType",
    "BrakeState",
    "Button",
    "Camera",
    "CanBufferMode",
    "CanMessage",
    "CanMessages",
    "CanNode",
    "Circle",
    "ClientCore",
    "Cluster",
    "CommandRejected",
    "ConnectionClosed",
    "DebugData",
    "DebugFrame",
    "EmergencyState",
    "Event",
    "Flag",
    "Frame",
    "GraphicColor",
    "GraphicObject",
    "GraphicType",
    "InvalidArgument",
    "Map",
    "MotionMode",
    "MotorIndex",
    "MouseButton",
    "ObservedLine",
    "OperationState",
    "OutputLevel",
    "ParamCategory",
    "ParamDataType",
    "ParamEntry",
    "PendingReply",
    "PlannerState",
    "PlatformClient",
    "PlatformError",
    "PltfParam",
    "PltfParamVec",
    "Point",
    "Pose",
    "Position",
    "Program",
    "ProtocolEntry",
    "ProtocolError",
    "Reply",
    "Roadmap",
    "ScanPoint",
    "Segment",
    "Status",
    "Timeout",
    "Variable",
    "WireLog",
    "format_param_value",
    "parse_param_value",
    "typed_reply",
]
