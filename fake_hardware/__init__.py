"""Fake hardware: the platform's CAN boards on a python-can bus and its laser scanner on a pyserial link.

Start at ``build_platform_hardware`` (``fake_hardware.hardware``) and ``fake_hardware/README.md``.
"""

from fake_hardware.board_status import BoardStatus
from fake_hardware.candb import ALL_NODES, MOTORS, Node, St
from fake_hardware.controller import CanController, CanRecord, ControllerError, HwEvent, SelfTestResult, Transaction
from fake_hardware.faults import Fault, FaultError, FaultInjector, FaultKind
from fake_hardware.hardware import Hardware, build_platform_hardware

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
