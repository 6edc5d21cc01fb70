"""The board sections of the CMD_GET_STATUS reply (guide 6.4), assembled from the frames the controller read.

Rules:
- ``BoardStatus`` has exactly the reply's field names (``spec/telegrams.yaml``), so the server can pass
  ``as_fields()`` straight into the telegram.
- A node that is not connected reports status ``St.ABSENT`` (-1) and zero readings (erratum E-HW-003). A node that
  stopped talking keeps its last readings; its status carries NODE_TIMEOUT (erratum E-HW-014).
- Unit conversions from the CAN database's physical values to the telegram's units live here and only here:
  temperatures degC (rounded), gyro values x 10000 (E-REP-008), relay keypad in bits 8-15 of
  relay_digital_in (erratum E-HW-011), ultrasonic analogue inputs 5-8 always 0 (E-REP-007).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields
from typing import Any

from pltf.fake_hardware.candb import Node, St

Readings = Mapping[str, Mapping[str, Any]]  # message function ("Encoder") -> last decoded signals


@dataclass(frozen=True)
class BoardStatus:
    relay_digital_in: int = 0
    relay_status: int = -1
    relay_analog_in: tuple[int, ...] = (0,) * 8
    relay_opto_distance: tuple[int, ...] = (0,) * 4
    io_battery_voltage: int = 0
    io_digital_in: int = 0
    io_digital_out: int = 0
    io_status: int = -1
    io_analog_in: tuple[int, ...] = (0,) * 8
    motor_right_status: int = -1
    motor_left_status: int = -1
    motor_right_temp: int = 0
    motor_left_temp: int = 0
    us_distance: tuple[int, ...] = (0,) * 16
    us_analog_in: tuple[int, ...] = (0,) * 8
    us_status: int = -1
    radar_velocity: tuple[int, ...] = (0,) * 4
    radar_status: int = -1
    gyro_accel: tuple[int, ...] = (0,) * 3
    gyro_angle: int = 0
    gyro_temp: int = 0
    gyro_status: int = -1

    def as_fields(self) -> dict[str, Any]:
        # Every value is an int or a tuple of ints (immutable): a shallow copy, not asdict's recursive deep copy
        # (which cost CMD_GET_STATUS half a millisecond).
        return {name: getattr(self, name) for name in _FIELD_NAMES}


_FIELD_NAMES = tuple(f.name for f in fields(BoardStatus))


def _ints(signals: Mapping[str, Any], names: list[str], scale: float = 1.0) -> tuple[int, ...]:
    return tuple(round(float(signals.get(n, 0)) * scale) for n in names)


def _analog(r: Readings, first: str, second: str | None) -> tuple[int, ...]:
    a = _ints(r.get(first, {}), [f"AnalogIn{i}" for i in range(1, 5)])
    b = _ints(r.get(second, {}), [f"AnalogIn{i}" for i in range(5, 9)]) if second else (0,) * 4
    return a + b


def _relay(r: Readings) -> dict[str, Any]:
    state = r.get("State", {})
    return {
        "relay_digital_in": int(state.get("DigIn", 0)) | int(state.get("Keypad", 0)) << 8,
        "relay_analog_in": _analog(r, "Analog1_4", "Analog5_8"),
        "relay_opto_distance": _ints(r.get("Opto", {}), [f"Distance{i}" for i in range(1, 5)]),
    }


def _io(r: Readings) -> dict[str, Any]:
    digital = r.get("Digital", {})
    return {
        "io_battery_voltage": round(float(r.get("Battery", {}).get("Voltage", 0))),
        "io_digital_in": int(digital.get("DigIn", 0)),
        "io_digital_out": int(digital.get("DigOut", 0)),
        "io_analog_in": _analog(r, "Analog1_4", "Analog5_8"),
    }


def _motor(side: str) -> Callable[[Readings], dict[str, Any]]:
    def readings(r: Readings) -> dict[str, Any]:
        return {f"motor_{side}_temp": round(float(r.get("State", {}).get("Temperature", 0)))}

    return readings


def _us(r: Readings) -> dict[str, Any]:
    distances: tuple[int, ...] = ()
    if not int(r.get("Status", {}).get("Status", 0)) & St.MEASURING:  # stopped: no measurement (E-HW-012)
        return {"us_distance": (0,) * 16, "us_analog_in": _analog(r, "Analog1_4", None)}
    for k in range(4):
        first = 4 * k + 1
        group = r.get(f"Distances{first}_{first + 3}", {})
        distances += _ints(group, [f"Distance{i}" for i in range(first, first + 4)])
    return {"us_distance": distances, "us_analog_in": _analog(r, "Analog1_4", None)}


def _radar(r: Readings) -> dict[str, Any]:
    return {"radar_velocity": _ints(r.get("Velocity", {}), [f"Velocity{i}" for i in range(1, 5)])}


def _gyro(r: Readings) -> dict[str, Any]:
    angle = r.get("Angle", {})
    return {
        "gyro_accel": _ints(r.get("Accel", {}), ["AccelX", "AccelY", "AccelZ"], 10_000),
        "gyro_angle": round(float(angle.get("Angle", 0)) * 10_000),
        "gyro_temp": round(float(angle.get("Temperature", 0)) * 10_000),
    }


SECTIONS: dict[Node, tuple[str, Callable[[Readings], dict[str, Any]]]] = {
    Node.RELAYBOARD: ("relay_status", _relay),
    Node.IOBOARD: ("io_status", _io),
    Node.MOTOR_RIGHT: ("motor_right_status", _motor("right")),
    Node.MOTOR_LEFT: ("motor_left_status", _motor("left")),
    Node.USBOARD: ("us_status", _us),
    Node.RADARBOARD: ("radar_status", _radar),
    Node.GYROBOARD: ("gyro_status", _gyro),
}


def assemble(readings: Mapping[Node, Readings], status: Mapping[Node, int]) -> BoardStatus:
    """The snapshot: ``readings`` of the connected nodes only, ``status`` words of every node (ABSENT or not)."""
    fields: dict[str, Any] = {}
    for node, (status_field, convert) in SECTIONS.items():
        fields[status_field] = status.get(node, -1)
        if node in readings:
            fields.update(convert(readings[node]))
    return BoardStatus(**fields)
