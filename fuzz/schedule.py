"""The case stream and the state plan.

Rules:
- Case ``i`` of a campaign is a function of (seed, i, corpus, what the target told us): its generator draws
  from ``random.Random(f"{seed}:{i}")`` only, so a run is reproducible from ``--seed`` and a resumed run
  (``--corpus``) continues the stream at the saved index instead of repeating it.
- The safety filter runs last, on the final bytes: a case any plausible reader could see a forbidden id in
  is dropped and drawn again (a bounded number of times).
- Cost-aware: a case over ``BIG_CASE`` bytes (a 300,000-point map of 8 MB, a 1 MiB string) costs the target
  0.05-0.6 s - as much as a thousand small cases - and such cases are a handful of fixed documents and values;
  the scheduler keeps ``big_share`` of the ones it draws (default ``BIG_SHARE``) and draws again for the rest,
  so they take a few percent of the target's time instead of a third. ``big_share=1`` is the natural mix.
- The state plan (guide 4.2 figure 2, 6.3 CMD_SET_MODE) walks every operation state, and every motion mode
  where a mode applies; ``prelude`` is the valid traffic that drives the target there from anywhere.
"""

from __future__ import annotations

import random
from dataclasses import replace
from typing import Any

from pltf.fuzz import generate, mutate
from pltf.fuzz.case import Case
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.wire import CLOSE, KEEP, forbidden_ids, survey
from pltf.spec.codec import REQUESTS, encode
from pltf.spec.model import enum_classes

MAX_DRAWS = 20
BIG_CASE = 1 << 20  # bytes
BIG_SHARE = 0.25  # of the drawn cases over BIG_CASE that are kept
GEN_SHARE = 0.55  # of cases drawn by a generator; the rest mutate a valid seed
MODES = sorted(int(v) for v in enum_classes()["MotionMode"])
OP: Any = enum_classes()["OperationState"]  # built from the spec at import: untyped for mypy


def _enc(telegram: str, **fields: Any) -> bytes:
    return encode(REQUESTS[telegram](**fields))


# (state, reported operation state, frames from anywhere). Mode-dependent states get SET_MODE appended.
_RESET = [_enc("CMD_STOP"), _enc("CMD_SHUTDOWN_PLTF")]
_UP = [*_RESET, _enc("CMD_CONNECT_TO_PLTF")]
_READY = [*_UP, _enc("CMD_INIT_PLTF")]
STATES: dict[str, tuple[int, list[bytes], bool]] = {
    # name: (reported ST_OP_*, prelude, needs motion)
    "not_connected": (OP.ST_OP_NOT_INITIALIZED, _RESET, False),
    "connected": (OP.ST_OP_NOT_INITIALIZED, _UP, False),
    "ready": (OP.ST_OP_READY, _READY, False),
    "running": (OP.ST_OP_RUNNING, _READY, True),
    "breaked": (OP.ST_OP_BREAKED, _READY, True),
}
# Tiny valid documents made active and saved at every state switch: a huge (or merely real) document saved
# by an earlier case would otherwise make every later LOAD_* cost the target milliseconds for the rest of the run.
TINY = {
    "map": '<?xml version="1.0"?><map Version="1.0"><layer index="0"/></map>',
    "roadmap": '<?xml version="1.0"?><roadmap Version="1.0"><stations><station id="a" name="A"><point x="0" y="0"/>'
    '</station><station id="b" name="B"><point x="1000" y="0"/></station></stations>'
    '<edges><edge startstation="a" endstation="b"/></edges></roadmap>',
    "program": '<?xml version="1.0"?><program version="1.0"><task name="t"><log type="info" message="m"/></task>'
    "</program>",
}


def _document_reset() -> list[bytes]:
    return [
        _enc("CMD_SET_MAP", name="fuzz.map", xml=TINY["map"]), _enc("CMD_SAVE_MAP"),
        _enc("CMD_SET_ROADMAP", name="fuzz.rm", xml=TINY["roadmap"]), _enc("CMD_SAVE_ROADMAP"),
        _enc("CMD_SET_PROGRAM", xml=TINY["program"]), _enc("CMD_SAVE_PROGRAM"),
    ]  # fmt: skip


DOCUMENT_RESET = _document_reset()
HARVEST = [
    _enc(n)
    for n in ("CMD_GET_PLTF_PARAM_VEC", "CMD_GET_ROADMAP", "CMD_GET_MAP", "CMD_GET_PROGRAM", "CMD_GET_POSITION",
              "CMD_GET_CAMERA", "CMD_GET_DEBUG_DATA")
]  # fmt: skip


class StatePlan:
    """Targets (state, mode) visited in turn; mode None where no mode applies."""

    def __init__(self, allow_motion: bool) -> None:
        self.targets: list[tuple[str, int | None]] = [("not_connected", None), ("connected", None)]
        for mode in MODES:  # mode-major, so that every state is visited early in a run
            for name, (_, _, motion) in STATES.items():
                if name not in ("not_connected", "connected") and (allow_motion or not motion):
                    self.targets.append((name, mode))
        self.index = 0
        self.reached: set[tuple[str, int | None]] = set()
        self.unreachable: set[tuple[str, int | None]] = set()

    @property
    def current(self) -> tuple[str, int | None]:
        return self.targets[self.index % len(self.targets)]

    def advance(self) -> None:
        self.index += 1

    @staticmethod
    def prelude(target: tuple[str, int | None]) -> list[bytes]:
        name, mode = target
        frames = list(STATES[name][1])
        if mode is not None:
            frames.append(_enc("CMD_SET_MODE", mode=mode))
        if name in ("running", "breaked"):
            frames.append(_enc("CMD_START"))
        if name == "breaked":
            frames.append(_enc("CMD_BREAK"))
        return frames

    @staticmethod
    def matches(target: tuple[str, int | None], operation_state: int | None, motion_mode: int | None) -> bool:
        name, mode = target
        return operation_state == STATES[name][0] and (mode is None or motion_mode == mode)


class Scheduler:
    def __init__(
        self, seed: int, forbidden: frozenset[int], kb: Knowledge, pool: list[Case] | None = None,
        big_share: float = BIG_SHARE,
    ) -> None:  # fmt: skip
        self.seed, self.forbidden, self.kb, self.big_share = seed, forbidden, kb, big_share
        self.pool: list[Case] = list(pool or [])
        self.dropped = 0
        gens = generate.GENERATORS
        self._gen_names = list(gens)
        self._gen_weights = [gens[n][0] for n in self._gen_names]
        self._mut_names = list(mutate.MUTATORS)
        self._mut_weights = [mutate.MUTATORS[n][0] for n in self._mut_names]

    def case(self, i: int) -> Case:
        rng = random.Random(f"{self.seed}:{i}")
        for _ in range(MAX_DRAWS):
            case = self._draw(rng)
            if not case.frames or not case.data:
                continue
            if case.size > BIG_CASE and rng.random() >= self.big_share:
                continue
            if forbidden_ids(case.data, self.forbidden):
                self.dropped += 1
                continue
            kind, answered = survey(case.data)
            return replace(case, expect=CLOSE if case.half_close else kind, answered=tuple(answered))
        return Case((_enc("CMD_GET_STATUS"),), "gen.fallback", "CMD_GET_STATUS", expect=KEEP)

    def _draw(self, rng: random.Random) -> Case:
        if rng.random() < GEN_SHARE:
            name = rng.choices(self._gen_names, self._gen_weights)[0]
            return generate.GENERATORS[name][1](rng, self.kb, self.forbidden)
        seed = self._seed_case(rng)
        name = rng.choices(self._mut_names, self._mut_weights)[0]
        return mutate.MUTATORS[name][1](seed, rng)

    def _seed_case(self, rng: random.Random) -> Case:
        if self.pool and rng.random() < 0.3:
            return rng.choice(self.pool)
        boundary = generate.GENERATORS["gen.boundary"][1]
        case = boundary(rng, self.kb, self.forbidden)
        if rng.random() < 0.2:  # a little valid conversation around it
            extra = boundary(rng, self.kb, self.forbidden)
            case = replace(case, frames=case.frames + extra.frames)
        return case
