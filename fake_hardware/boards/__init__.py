"""One simulator per CAN board; each is a node on a python-can bus (see ``base.Board``)."""

from fake_hardware.boards.base import Board, EmergencyCircuit
from fake_hardware.boards.gyro import GyroBoard
from fake_hardware.boards.ioboard import IoBoard
from fake_hardware.boards.motor import MotorBoard, MotorParams
from fake_hardware.boards.radar import RadarBoard
from fake_hardware.boards.relay import RelayBoard
from fake_hardware.boards.ultrasonic import UltrasonicBoard

__all__ = [
    "Board",
    "EmergencyCircuit",
    "GyroBoard",
    "IoBoard",
    "MotorBoard",
    "MotorParams",
    "RadarBoard",
    "RelayBoard",
    "UltrasonicBoard",
]
