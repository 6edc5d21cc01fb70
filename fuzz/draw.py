"""The compiled drawing core (``_draw.c``): the tables it is fed once, and a block of cases drawn by it.

Rules:
- ``_draw`` is an optional C extension (setup.py); ``AVAILABLE`` says whether it was built. Without it the
  scheduler draws every case in Python (``pltf.fuzz.schedule``): the same generators and mutators, another
  stream from the same seed.
- The tables are compiled from the spec (``pltf.spec.model.load_telegrams``), not written by hand: per request
  telegram its id, name, whether a server answers it, and its fields (wire type, repeat, constant, the allowed
  values sorted, the range, and the role a field plays for knowledge: a parameter key, a station name). The
  value tables (``STRINGS``) are ``pltf.fuzz.generate``'s.
- ``Drawer.block`` returns, for each case of the block, a ``Case`` or an *intent* the core leaves to Python:
  ``(TELEGRAM, id | hostile << 8, seed)`` a telegram with an XML field (its document comes from
  ``pltf.fuzz.xml_attacks`` or what the target sent), ``(LENGTH, id, seed)`` the same under a lying length,
  ``(XML, 0, seed)`` gen.xml, ``(POOL, 0, seed)`` a mutation of a corpus input, ``(FALLBACK, 0, 0)`` nothing safe
  was drawn. ``seed`` seeds the ``random.Random`` Python draws that case from, so the stream stays a function
  of (seed, i, what was learnt).
"""

from __future__ import annotations

import array
import functools
import itertools
from typing import Any

from pltf.fuzz import generate, mutate
from pltf.fuzz.case import WHOLE, Case, Delivery
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.wire import ANSWERED, CLOSE, CLOSE_SOCKET_ID, KEEP, PARTIAL
from pltf.spec.compiler import allowed_values, value_range
from pltf.spec.model import FieldDef, load_telegrams

try:
    from pltf.fuzz import _draw
except ImportError:  # built without a compiler, or PLTF_NO_EXTENSIONS=1
    _draw = None  # type: ignore[assignment]

AVAILABLE = _draw is not None
TELEGRAM, LENGTH, XML, POOL, FALLBACK = range(5)
KINDS = {"BYTE": 0, "BOOL": 1, "INT16": 2, "INT": 3, "DOUBLE": 4, "STRING": 5, "XML": 6, "GROUP": 7}
ROLE_PLAIN, ROLE_KEY, ROLE_STATION = range(3)
# the order _draw.c's enums expect
GENERATORS = ("gen.boundary", "gen.hostile", "gen.any_id", "gen.length_field", "gen.xml")
MUTATORS = (
    "mut.bit_flip",
    "mut.byte_set",
    "mut.header",
    "mut.length_lie",
    "mut.truncate",
    "mut.insert_delete",
    "mut.int_field",
    "mut.splice",
    "mut.bytewise",
    "mut.slow",
    "mut.half_close",
    "mut.flood",
)
# the origins the core names a case by, in its order: a mut.insert_delete case says which of the two it did
SPLIT = {"mut.insert_delete": ("mut.delete", "mut.insert")}
ORIGINS = (*GENERATORS[:4], *itertools.chain.from_iterable(SPLIT.get(m, (m,)) for m in MUTATORS))
I64 = (-(2**63), 2**63 - 1)


def _role(telegram: str, f: FieldDef) -> int:
    """Where ``pltf.fuzz.generate._string`` takes a string from what the target told us."""
    if telegram in ("CMD_SET_PLTF_PARAM", "CMD_GET_PLTF_PARAM") and f.name == "key":
        return ROLE_KEY
    return ROLE_STATION if telegram == "CMD_MOVE_TO_STATION" else ROLE_PLAIN


def _field(telegram: str, f: FieldDef) -> tuple[Any, ...]:
    allowed = allowed_values(f)
    rng = value_range(f)
    return (
        KINDS["GROUP" if f.is_group else f.type],
        f.repeat or 0,
        f.const,
        None if allowed is None else tuple(sorted(allowed)),
        None if rng is None else (max(rng[0], I64[0]), min(rng[1], I64[1])),
        [_field(telegram, g) for g in f.fields] if f.is_group else [],
        _role(telegram, f),
        f.name,
    )


def tables() -> list[tuple[Any, ...]]:
    """Every telegram a strict server reads as a request (an unknown layout: any payload), with its fields."""
    out = []
    for t in load_telegrams():
        layout = t.request if t.layout_known else None
        fields = [_field(t.name, f) for f in layout or ()]
        out.append((t.id, t.name, layout is None, t.id in ANSWERED, t.name == "CMD_MOVE_PATH", fields))
    return out


@functools.cache
def _setup() -> None:
    assert _draw is not None
    deliveries = (WHOLE, Delivery("bytewise"), *(Delivery("slow", n, 0.001) for n in (2, 3, 4)))
    small, large = generate.BIG_STRING_SIZES
    _draw.setup(
        tables(),
        CLOSE_SOCKET_ID,
        tuple(generate.STRINGS),
        ORIGINS,
        Case,
        deliveries,
        (KEEP, CLOSE, PARTIAL),
        mutate.GET_STATUS,
        (b"B" * small, b"B" * large),
    )


def survey(data: bytes) -> tuple[str, tuple[int, ...]] | None:
    """``pltf.fuzz.wire.survey`` in C (None: not built, or more answered ids than it keeps)."""
    if _draw is None:
        return None
    _setup()
    return _draw.survey(data)


def mask(ids: frozenset[int]) -> bytes:
    return bytes(i in ids for i in range(256))


def _cum(weights: Any) -> bytes:
    return array.array("d", itertools.accumulate(weights)).tobytes()


class Drawer:
    """Blocks of cases for one seed and one set of forbidden ids."""

    def __init__(self, seed: int, forbidden: frozenset[int], big_share: float) -> None:
        assert _draw is not None
        _setup()
        defs = generate.request_defs(forbidden)
        self.seed, self.big_share, self.mask = seed, big_share, mask(forbidden)
        self.picks = bytes(t.id for t in defs)
        self.pick_cum = _cum(generate.HEAVY_WEIGHT if t.name in generate.HEAVY else 1.0 for t in defs)
        self.free_ids = bytes(i for i in range(256) if i not in forbidden)
        self.gen_cum = _cum(generate.GENERATORS[n][0] for n in GENERATORS)
        self.mut_cum = _cum(mutate.MUTATORS[n][0] for n in MUTATORS)

    def block(self, number: int, n: int, kb: Knowledge, pool: bool) -> tuple[list[Any], int]:
        """(a ``Case`` or an intent per case, cases dropped as unsafe) of block ``number``."""
        assert _draw is not None
        keys = [k.encode("latin-1", "replace") for k in kb.param_keys]
        stations = [s.encode("latin-1", "replace") for s in kb.stations]
        x, y, angle = kb.pose
        return _draw.block(
            self.seed & (2**64 - 1),
            number,
            n,
            self.mask,
            self.picks,
            self.pick_cum,
            self.free_ids,
            self.gen_cum,
            self.mut_cum,
            keys,
            stations,
            (int(x), int(y), int(angle)),
            pool,
            self.big_share,
        )
