"""Post-process recording and replay (guide 6.3 CMD_SET_EVENT, motion mode POST_PROCESS_REPLAY).

Rules (erratum E-MOT-010):
- EV_START_POST_PROCESS_RECORDING clears the recording and samples the estimated pose every control period
  until EV_STOP_POST_PROCESS_RECORDING, in any motion mode; it is kept in memory (CMD_SET_POST_PROCESS_FILENAME
  is "not used at the moment").
- EV_START_POST_PROCESS_REPLAY (mode POST_PROCESS_REPLAY, Running): the platform first drives to the first
  recorded pose like a CMD_MOVE_ABS, then follows the recording in time, tracking each recorded pose at its
  recorded time offset (Kanayama's law with the recorded velocities as feed-forward). BREAK/CONTINUE pause
  and resume the replay clock; STOP ends the replay.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pltf.reference_server.world.automatic import AutoJob, Navigator, Perception
from pltf.reference_server.world.geometry import F64
from pltf.reference_server.world.ipo import Ref, track
from pltf.reference_server.world.planner import PlannerState

Params = Callable[[str], Any]
Pose = tuple[float, float, float]


@dataclass
class Recorder:
    recording: bool = False
    samples: list[tuple[float, float, float, float]] = field(default_factory=list)  # t, x, y, angle

    def start(self) -> None:
        self.recording, self.samples = True, []

    def stop(self) -> None:
        self.recording = False

    def sample(self, now: float, pose: Pose) -> None:
        if self.recording:
            self.samples.append((now, *pose))


@dataclass
class ReplayJob:
    table: F64  # (N, 4): t from 0, x, y, unwrapped angle
    approach: AutoJob
    phase: str = "approach"
    t: float = 0.0
    paused: bool = False
    events: list[str] = field(default_factory=list)

    @classmethod
    def of(cls, samples: list[tuple[float, float, float, float]], planning: bool) -> ReplayJob | None:
        if len(samples) < 2:
            return None
        table = np.asarray(samples, dtype=np.float64)
        table[:, 0] -= table[0, 0]
        table[:, 3] = np.unwrap(table[:, 3])
        first = (float(table[0, 1]), float(table[0, 2]), float(table[0, 3]))
        return cls(table, AutoJob("goto", first, [first], planning))

    @property
    def done(self) -> bool:
        return self.phase == "done"

    @property
    def duration(self) -> float:
        return float(self.table[-1, 0])

    @property
    def planner_state(self) -> PlannerState:
        return self.approach.planner_state if self.phase == "approach" else PlannerState.STANDBY

    def reference(self, pose: Pose) -> Ref:
        if self.phase == "approach":
            return self.approach.reference(pose)
        tb = self.table
        t = min(self.t, self.duration)
        x, y, a = (float(np.interp(t, tb[:, 0], tb[:, k])) for k in (1, 2, 3))
        if self.paused or self.t >= self.duration:
            return Ref(x, y, a, 0.0, 0.0)
        dt = 0.05
        x1, y1, a1 = (float(np.interp(min(t + dt, self.duration), tb[:, 0], tb[:, k])) for k in (1, 2, 3))
        h = max(min(t + dt, self.duration) - t, 1e-9)
        v = ((x1 - x) * math.cos(a) + (y1 - y) * math.sin(a)) / h
        return Ref(x, y, a, v, (a1 - a) / h)

    def path_points(self) -> F64:
        if self.phase == "approach":
            return self.approach.path_points()
        rest = self.table[self.table[:, 0] >= self.t]
        return np.ascontiguousarray(rest[::5, 1:3])

    def step(
        self, now: float, dt: float, pose: Pose, seen: Perception, p: Params, nav: Navigator, speed: float = 0.0
    ) -> tuple[float, float]:
        if self.phase == "approach":
            v, w = self.approach.step(now, dt, pose, seen, p, nav, speed)
            self.events += self.approach.events
            self.approach.events = []
            if not self.approach.done:
                return v, w
            if self.approach.planner_state not in (PlannerState.STANDBY, PlannerState.PATH_FOUND):
                self.phase = "done"
                return 0.0, 0.0
            self.phase = "replay"
            self.events.append(f"replay: {self.duration:.1f} s of recorded motion")
        if self.phase != "replay":
            return 0.0, 0.0
        if not self.paused:
            self.t += dt
        if self.t >= self.duration + 1.0:
            self.phase = "done"
            self.events.append("replay finished")
            return 0.0, 0.0
        ref = self.reference(pose)
        turning = abs(ref.v) < 1.0
        return track(pose, ref, turning, p)
