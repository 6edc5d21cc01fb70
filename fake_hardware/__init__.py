"""Fake hardware: the platform's CAN boards on a python-can bus and its laser scanner on a pyserial link.

Start at ``build_platform_hardware`` (``pltf.fake_hardware.hardware``) and ``fake_hardware/README.md``.
"""

from pltf.fake_hardware.board_status import BoardStatus
from pltf.fake_hardware.candb import ALL_NODES, MOTORS, Node, St
from pltf.fake_hardware.controller import (
    CanController,
    CanRecord,
    ControllerError,
    HwEvent,
    SelfTestResult,
    Transaction,
)
from pltf.fake_hardware.faults import Fault, FaultError, FaultInjector, FaultKind
from pltf.fake_hardware.hardware import Hardware, build_platform_hardware

__all__ = [
    "ALL_NODES",
    "MOTORS",
    "BoardStatus",
    "CanController",
    "CanRecord",
    "ControllerError",
    "Fault",
    "FaultError",
    "FaultInjector",
    "FaultKind",
    "Hardware",
    "HwEvent",
    "Node",
    "SelfTestResult",
    "St",
    "Transaction",
    "build_platform_hardware",
]
