"""The case stream (the state plan is ``pltf.fuzz.preludes``).

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
"""

from __future__ import annotations

import itertools
import random
from dataclasses import replace
from typing import Any

from pltf.fuzz import generate, mutate
from pltf.fuzz.case import Case
from pltf.fuzz.generate import weighted
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.wire import CLOSE, KEEP, forbidden_ids, survey
from pltf.spec.codec import REQUESTS, encode

MAX_DRAWS = 20
BIG_CASE = 1 << 20  # bytes
BIG_SHARE = 0.25  # of the drawn cases over BIG_CASE that are kept
GEN_SHARE = 0.55  # of cases drawn by a generator; the rest mutate a valid seed


def _enc(telegram: str, **fields: Any) -> bytes:
    return encode(REQUESTS[telegram](**fields))


class Scheduler:
    def __init__(
        self,
        seed: int,
        forbidden: frozenset[int],
        kb: Knowledge,
        pool: list[Case] | None = None,
        big_share: float = BIG_SHARE,
    ) -> None:
        self.seed, self.forbidden, self.kb, self.big_share = seed, forbidden, kb, big_share
        self.pool: list[Case] = list(pool or [])
        self.dropped = 0
        gens = generate.GENERATORS
        self._gen_names = list(gens)
        self._gen_cum = list(itertools.accumulate(gens[n][0] for n in self._gen_names))
        self._mut_names = list(mutate.MUTATORS)
        self._mut_cum = list(itertools.accumulate(mutate.MUTATORS[n][0] for n in self._mut_names))
        self._rng = random.Random()  # seeded again for each case: the stream of ``random.Random(f"{seed}:{i}")``

    def case(self, i: int) -> Case:
        rng = self._rng
        rng.seed(f"{self.seed}:{i}")
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
            return case.judged(CLOSE if case.half_close else kind, tuple(answered))
        return Case((_enc("CMD_GET_STATUS"),), "gen.fallback", "CMD_GET_STATUS", expect=KEEP)

    def _draw(self, rng: random.Random) -> Case:
        if rng.random() < GEN_SHARE:
            name = weighted(rng, self._gen_names, self._gen_cum)
            return generate.GENERATORS[name][1](rng, self.kb, self.forbidden)
        seed = self._seed_case(rng)
        name = weighted(rng, self._mut_names, self._mut_cum)
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
