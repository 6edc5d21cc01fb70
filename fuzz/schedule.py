"""The case stream (the state plan is ``pltf.fuzz.preludes``).

Rules:
- Case ``i`` of a campaign is a function of (seed, i, corpus, what the target told us): the cases of a block of
  ``BLOCK`` (``i // BLOCK``) draw one after the other from ``random.Random(f"{seed}:b{i // BLOCK}")`` only, so a
  run is reproducible from ``--seed`` and a resumed run (``--corpus``) continues the stream at the saved index
  instead of repeating it. (Seeded per case, as before issue 34, the seeding alone - a SHA-512 and the
  Mersenne Twister's 624-word set-up - took ~9 us of a case's ~41 us of drawing.) A case asked for out of turn is
  drawn behind the ones before it in its block, drawn again and dropped.
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

from pltf.fuzz import draw, generate, mutate
from pltf.fuzz.case import Case
from pltf.fuzz.generate import weighted
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.wire import CLOSE, KEEP, forbidden_ids, survey
from pltf.spec.codec import REQUESTS, encode

MAX_DRAWS = 20
BLOCK = 256  # cases drawn from one seeding of the generator
LOOK_KEPT_FROM = 1 << 16  # bytes: what the scheduler saw in data this big is remembered by the data's object
LOOKS_KEPT = 64
BIG_CASE = 1 << 20  # bytes
BIG_SHARE = 0.25  # of the drawn cases over BIG_CASE that are kept
GEN_SHARE = 0.55  # of cases drawn by a generator; the rest mutate a valid seed


def _enc(telegram: str, **fields: Any) -> bytes:
    return encode(REQUESTS[telegram](**fields))


GEN_NAMES = ("gen.boundary", "gen.hostile")


def _survey(data: bytes) -> tuple[str, tuple[int, ...] | list[int]]:
    """``survey`` in C when the core is built (the tests hold the two equal)."""
    return draw.survey(data) or survey(data)


class Scheduler:
    def __init__(
        self,
        seed: int,
        forbidden: frozenset[int],
        kb: Knowledge,
        pool: list[Case] | None = None,
        big_share: float = BIG_SHARE,
        compiled: bool = True,
    ) -> None:
        self.seed, self.forbidden, self.kb, self.big_share = seed, forbidden, kb, big_share
        self.pool: list[Case] = list(pool or [])
        self.dropped = 0
        gens = generate.GENERATORS
        self._gen_names = list(gens)
        self._gen_cum = list(itertools.accumulate(gens[n][0] for n in self._gen_names))
        self._mut_names = list(mutate.MUTATORS)
        self._mut_cum = list(itertools.accumulate(mutate.MUTATORS[n][0] for n in self._mut_names))
        self._rng = random.Random()  # seeded again for each block of ``BLOCK`` cases
        self._at: int | None = None  # the case the generator's state is at (None: not seeded yet)
        self._looked: dict[int, tuple[bytes, bool, str, tuple[int, ...]]] = {}  # id(data) -> (data, ``_look``)
        self._drawer = draw.Drawer(seed, forbidden, big_share) if compiled and draw.AVAILABLE else None
        self._block: tuple[int, list[Case]] = (-1, [])  # the block drawn last and its cases
        self._counted = -1  # the last block whose unsafe cases were counted in ``dropped``

    @property
    def compiled(self) -> bool:
        """The compiled core draws (``pltf.fuzz.draw``): a window costs ~3 us a case, drawn where it is taken."""
        return self._drawer is not None

    def window(self, first: int, n: int) -> list[Case]:
        """Cases ``first`` to ``first + n - 1``, a block's slice at a time."""
        if self._drawer is None:
            return [self.case(i) for i in range(first, first + n)]
        out: list[Case] = []
        i, end = first, first + n
        while i < end:
            self._compiled(i)
            stop = min(end, i - i % BLOCK + BLOCK)
            out += self._block[1][i % BLOCK : i % BLOCK + stop - i]
            i = stop
        return out

    def _compiled(self, i: int) -> Case:
        """Case ``i`` from its block, drawn whole by the compiled core (``pltf.fuzz.draw``) when first asked for;
        the cases it leaves to Python drawn here, each from a ``random.Random`` seeded by the core."""
        number, cases = self._block
        if number != i // BLOCK:
            assert self._drawer is not None
            number = i // BLOCK
            items, dropped = self._drawer.block(number, BLOCK, self.kb, bool(self.pool))
            cases = [c if isinstance(c, Case) else self._intent(*c) for c in items]
            if number > self._counted:  # a block drawn again (asked for out of turn) was counted the first time
                self.dropped += dropped
                self._counted = number
            self._block = (number, cases)
        return cases[i % BLOCK]

    def _intent(self, intent: int, ident: int, seed: int) -> Case:
        """A case the compiled core leaves to Python (``pltf.fuzz.draw``): an XML document, a corpus input."""
        rng = random.Random(seed)
        for _ in range(MAX_DRAWS if intent != draw.FALLBACK else 0):
            case = self._draw_intent(intent, ident, rng)
            checked = self._checked(case, rng)
            if checked is not None:
                return checked
        return Case((_enc("CMD_GET_STATUS"),), "gen.fallback", "CMD_GET_STATUS", expect=KEEP)

    def _draw_intent(self, intent: int, ident: int, rng: random.Random) -> Case:
        if intent == draw.POOL:
            name = weighted(rng, self._mut_names, self._mut_cum)
            return mutate.MUTATORS[name][1](rng.choice(self.pool), rng)
        if intent == draw.XML:
            return generate.GENERATORS["gen.xml"][1](rng, self.kb, self.forbidden)
        tdef = generate.request_def(ident & 0xFF)
        if intent == draw.LENGTH:
            return generate.length_field_case(tdef, rng, self.kb)
        hostile = bool(ident >> 8)
        return generate.gen_telegram(tdef, rng, self.kb, 0.35 if hostile else 0.0, GEN_NAMES[hostile])

    def case(self, i: int) -> Case:
        if self._drawer is not None:
            return self._compiled(i)
        if self._at != i:  # out of turn: the block's cases before it, drawn again
            start = i - i % BLOCK
            self._rng.seed(f"{self.seed}:b{start // BLOCK}")
            self._at, dropped = start, self.dropped
            while self._at < i:
                self._next()
            self.dropped = dropped  # those were counted when they were drawn in turn (or never ran)
        return self._next()

    def _next(self) -> Case:
        """The case the generator is at; the state then moves to the next one (seeded again at a block's end)."""
        case = self._draw_checked(self._rng)
        self._at = at = (self._at or 0) + 1
        if at % BLOCK == 0:
            self._rng.seed(f"{self.seed}:b{at // BLOCK}")
        return case

    def _draw_checked(self, rng: random.Random) -> Case:
        for _ in range(MAX_DRAWS):
            checked = self._checked(self._draw(rng), rng)
            if checked is not None:
                return checked
        return Case((_enc("CMD_GET_STATUS"),), "gen.fallback", "CMD_GET_STATUS", expect=KEEP)

    def _checked(self, case: Case, rng: random.Random) -> Case | None:
        """The case with what a strict server does with it, or None: empty, a big one not kept, or unsafe."""
        if not case.frames or not case.data:
            return None
        if case.size > BIG_CASE and rng.random() >= self.big_share:
            return None
        forbidden, kind, answered = self._look(case.data)
        if forbidden:
            self.dropped += 1
            return None
        return case.judged(CLOSE if case.half_close else kind, answered)

    def _look(self, data: bytes) -> tuple[bool, str, tuple[int, ...]]:
        """(a forbidden id in it, ``survey``'s kind and answered ids) of ``data``; remembered for big data, whose
        object comes again (a document's frame, ``pltf.fuzz.generate``): scanning megabytes twice per draw was
        most of the cost of drawing a big document."""
        if len(data) < LOOK_KEPT_FROM:
            kind, answered = _survey(data)
            return bool(forbidden_ids(data, self.forbidden)), kind, tuple(answered)
        known = self._looked.get(id(data))
        if known is None or known[0] is not data:
            kind, answered = _survey(data)
            if len(self._looked) >= LOOKS_KEPT:
                self._looked.clear()
            known = self._looked[id(data)] = (data, bool(forbidden_ids(data, self.forbidden)), kind, tuple(answered))
        return known[1], known[2], known[3]

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
