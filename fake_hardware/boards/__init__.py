"""One simulator per CAN board; each is a node on a python-can bus (see ``base.Board``)."""

from pltf.fake_hardware.boards.base import Board, EmergencyCircuit
from pltf.fake_hardware.boards.gyro import GyroBoard
from pltf.fake_hardware.boards.ioboard import IoBoard
from pltf.fake_hardware.boards.motor import MotorBoard, MotorParams
from pltf.fake_hardware.boards.radar import RadarBoard
from pltf.fake_hardware.boards.relay import RelayBoard
from pltf.fake_hardware.boards.ultrasonic import UltrasonicBoard

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
