"""A parsed program (guide 6.5 Program, Task): frozen dataclasses, one per element of the task language.

Rules:
- One class per command element; every command knows its source ``line`` and its element name ``tag`` (for
  logs and the progress view). Units are converted once, here: angles stay degrees (E-XML-007), durations
  milliseconds (E-XML-009); the actuators convert to what their wire or model needs.
- A ``Task`` is a flat list of commands with its label table (guide: "a sequence of commands including branch
  commands and labels"); ``Program.task`` finds a task the way onErrorTask names it (E-XML-022).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field


class Entity(enum.Enum):
    """What <moveto> drives to (guide 6.5 <moveto>: trackedperson | trackedball | ...)."""

    PERSON = "trackedperson"
    BALL = "trackedball"
    MOVING_OBJECT = "trackedmovingobject"
    CHARGING_STATION = "chargingstation"


class Direction(enum.IntEnum):
    """E-TASK-011: <infrared>/<radar> direction -> IR sensor / radar sensor #1..#4 of the status telegram."""

    FRONT = 0
    BACK = 1
    LEFT = 2
    RIGHT = 3


DIRECTIONS: dict[str, Direction | None] = {
    "front": Direction.FRONT,
    "1": Direction.FRONT,
    "back": Direction.BACK,
    "rear": Direction.BACK,
    "2": Direction.BACK,
    "left": Direction.LEFT,
    "3": Direction.LEFT,
    "right": Direction.RIGHT,
    "4": Direction.RIGHT,
    "any": None,
    "all": None,
}


class Detection(enum.Enum):
    """What a detection wait waits for (E-XML-004: both spellings map to one member)."""

    MOVING_OBJECT = "movingobject"
    PERSON = "person"
    BALL = "ball"


@dataclass(frozen=True)
class Command:
    line: int

    @property
    def tag(self) -> str:
        return TAGS[type(self)]


# ---- commands with an effect on the platform
@dataclass(frozen=True)
class DigitalOut(Command):
    states: tuple[int, ...]  # D1..D12: -1 unchanged, 0 off, 1 on (E-XML-023)


@dataclass(frozen=True)
class Load(Command):
    map: str | None
    roadmap: str | None


@dataclass(frozen=True)
class Log(Command):
    type: str
    message: str


@dataclass(frozen=True)
class Stop(Command):
    pass


@dataclass(frozen=True)
class MoveCoord(Command):
    x: float  # mm
    y: float  # mm
    angle: float  # degrees (E-XML-007)


@dataclass(frozen=True)
class MoveStation(Command):
    name: str


@dataclass(frozen=True)
class MoveTo(Command):
    entity: Entity
    on_error_task: str | None


@dataclass(frozen=True)
class SetParameter(Command):
    key: str
    value: str


@dataclass(frozen=True)
class Grab(Command):
    filename: str
    scan: bool
    image: bool
    auto_observation: bool


@dataclass(frozen=True)
class MoveCamera(Command):
    position: str


@dataclass(frozen=True)
class Speak(Command):
    text: str


@dataclass(frozen=True)
class Play(Command):
    filename: str


@dataclass(frozen=True)
class TurnHead(Command):
    angle: float  # degrees (E-XML-007)


# ---- control flow
@dataclass(frozen=True)
class Label(Command):
    name: str


@dataclass(frozen=True)
class Goto(Command):
    label: str
    condition: str  # E-XML-013 text; "true" when absent


# ---- waits: the event (None: an empty <wait>, E-XML-019) and the timeout
@dataclass(frozen=True)
class Collision:
    pass


@dataclass(frozen=True)
class Detected:
    what: Detection


@dataclass(frozen=True)
class LostLocalization:
    pass


@dataclass(frozen=True)
class TargetReached:
    pass


@dataclass(frozen=True)
class Infrared:
    direction: Direction | None  # None: any sensor


@dataclass(frozen=True)
class Radar:
    direction: Direction | None  # None: any sensor


@dataclass(frozen=True)
class Date:
    """Absent fields match any value (E-XML-024)."""

    year: int | None = None
    month: int | None = None
    day: int | None = None
    hour: int | None = None
    minute: int | None = None
    second: int | None = None


@dataclass(frozen=True)
class Delay:
    ms: float


@dataclass(frozen=True)
class UserEvent:
    id: str


@dataclass(frozen=True)
class Random:
    min_ms: float
    max_ms: float


@dataclass(frozen=True)
class BatteryCharge:
    limit: float  # percent (E-XML-024)


WaitEvent = (
    Collision
    | Detected
    | LostLocalization
    | TargetReached
    | Infrared
    | Radar
    | Date
    | Delay
    | UserEvent
    | Random
    | BatteryCharge
)


@dataclass(frozen=True)
class Wait(Command):
    event: WaitEvent | None
    timeout_ms: float | None  # None: no timeout (absent or 0, E-XML-009)
    timeout_label: str | None


TAGS: dict[type[Command], str] = {
    DigitalOut: "ioevent",
    Load: "load",
    Log: "log",
    Stop: "motion stop",
    MoveCoord: "motion settarget coord",
    MoveStation: "motion settarget station",
    MoveTo: "motion moveto",
    SetParameter: "parameter set",
    Grab: "surveillance grab",
    MoveCamera: "surveillance movecamera",
    Speak: "audio speak",
    Play: "audio play",
    TurnHead: "turnhead",
    Label: "label",
    Goto: "goto",
    Wait: "wait",
}


@dataclass(frozen=True, eq=False)  # identity: two tasks with equal text are still two tasks
class Task:
    name: str
    id: str
    priority: int  # E-XML-022: larger is higher; non-integer or absent: 0
    commands: tuple[Command, ...]
    labels: dict[str, int] = field(default_factory=dict)  # label name -> index of the <label> command
    line: int = 0

    @property
    def title(self) -> str:
        return self.name or self.id or f"task@{self.line}"


@dataclass(frozen=True)
class Program:
    tasks: tuple[Task, ...]

    def task(self, name: str) -> Task | None:
        """E-XML-022: onErrorTask matches a task's name exactly, else its id."""
        for task in self.tasks:
            if task.name == name:
                return task
        for task in self.tasks:
            if task.id == name:
                return task
        return None

    def handlers(self) -> frozenset[Task]:
        """The tasks some <moveto onErrorTask> names: they run only on error (E-TASK-002)."""
        named = (cmd.on_error_task for t in self.tasks for cmd in t.commands if isinstance(cmd, MoveTo))
        return frozenset(task for name in named if name is not None and (task := self.task(name)) is not None)
