"""A facade.Machine made of plain attributes: the tests set the sensors and read back the actions."""

from __future__ import annotations

import datetime
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from pltf.reference_server.tasks.facade import Pose, Target, TaskError
from pltf.reference_server.tasks.model import Detection, Direction, Entity
from pltf.spec.parameters import DataType

EPOCH = datetime.datetime(2030, 1, 1)


@dataclass
class FakeMachine:
    actions: list[tuple[Any, ...]] = field(default_factory=list)
    outputs: list[int] = field(default_factory=lambda: [0] * 12)
    inputs: list[int] = field(default_factory=lambda: [0] * 16)
    params: dict[str, tuple[DataType, str]] = field(default_factory=lambda: {"MaxTransVel": (DataType.INTEGER, "600")})
    where: Pose = field(default_factory=lambda: Pose(0.0, 0.0, 0.0))
    reached: bool = False
    flags: dict[str, bool] = field(default_factory=dict)  # collision, lost, person, ball, movingobject
    ir: list[bool] = field(default_factory=lambda: [False] * 4)
    radar_on: list[bool] = field(default_factory=lambda: [False] * 4)
    battery: float = 50.0
    entities: dict[Entity, Target] = field(default_factory=dict)
    events: set[str] = field(default_factory=set)
    files: set[str] = field(default_factory=set)

    # ---- actuators
    def set_digital_outputs(self, states: Sequence[int]) -> None:
        for i, s in enumerate(states):
            if s != -1:
                self.outputs[i] = s
        self.actions.append(("digout", tuple(states)))

    def move_to_pose(self, x: float, y: float, angle: float) -> None:
        self.reached = False
        self.actions.append(("move", round(x), round(y), round(angle, 3)))

    def move_to_station(self, name: str) -> None:
        self.reached = False
        self.actions.append(("station", name))

    def stop_motion(self) -> None:
        self.actions.append(("stop",))

    def set_parameter(self, key: str, value: str) -> None:
        if key not in self.params:
            raise TaskError(f"unknown parameter {key}")
        self.params[key] = (self.params[key][0], value)
        self.actions.append(("param", key, value))

    def load(self, map_name: str | None, roadmap_name: str | None) -> None:
        for name in (map_name, roadmap_name):
            if name is not None and name not in self.files:
                raise TaskError(f"no file {name}")
        self.actions.append(("load", map_name, roadmap_name))

    def log(self, type: str, message: str) -> None:
        self.actions.append(("log", type, message))

    def grab(self, filename: str, scan: bool, image: bool, auto_observation: bool) -> list[str]:
        self.actions.append(("grab", filename, scan, image))
        return [f"{filename}.dat"] * scan + [f"{filename}.jpg"] * image

    def move_camera(self, position: str) -> None:
        self.actions.append(("camera", position))

    def speak(self, text: str) -> None:
        self.actions.append(("speak", text))

    def play(self, filename: str) -> None:
        self.actions.append(("play", filename))

    def turn_head(self, angle: float) -> None:
        self.actions.append(("head", angle))

    # ---- sensors
    def begin_tick(self, now: float) -> None:
        pass

    def pose(self) -> Pose:
        return self.where

    def target_reached(self) -> bool:
        return self.reached

    def collision(self) -> bool:
        return self.flags.get("collision", False)

    def detected(self, what: Detection) -> bool:
        return self.flags.get(what.value, False)

    def localization_lost(self) -> bool:
        return self.flags.get("lost", False)

    def infrared(self, direction: Direction | None) -> bool:
        return any(self.ir) if direction is None else self.ir[direction]

    def radar(self, direction: Direction | None) -> bool:
        return any(self.radar_on) if direction is None else self.radar_on[direction]

    def battery_percent(self) -> float:
        return self.battery

    def digital_input(self, n: int) -> int:
        return self.inputs[n - 1]

    def digital_output(self, n: int) -> int:
        return self.outputs[n - 1]

    def parameter(self, key: str) -> tuple[DataType, str]:
        if key not in self.params:
            raise TaskError(f"unknown parameter {key}")
        return self.params[key]

    def entity(self, what: Entity) -> Target | None:
        return self.entities.get(what)

    def take_user_events(self) -> frozenset[str]:
        out, self.events = frozenset(self.events), set()
        return out

    def local_time(self, now: float) -> datetime.datetime:
        return EPOCH + datetime.timedelta(seconds=now)

    def of(self, kind: str) -> list[tuple[Any, ...]]:
        return [a for a in self.actions if a[0] == kind]
