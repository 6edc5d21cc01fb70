"""A long telegram's big groups as numpy columns, the rest decoded by the codec (issue 35: the MCAP export).

A CMD_GET_STATUS reply carries its scan as a group of 541 ScanPoint items (guide 6.4): the codec builds a
namedtuple per item (~90 us a reply), the export needs the items as two arrays and the view's line only the first
three. ``split`` walks the telegram's layout (spec/telegrams.yaml, the field table the codec is compiled from) and
cuts each *plain* group - fixed-size items without enums, ranges or constants, the groups the codec itself decodes
without a check per item (spec/compiler.py, ``simple``) - to its first ``keep`` items, rewriting the count. The
codec then decodes the shortened telegram, checking everything it would check in the whole one (the cut items
have nothing to check); the cut groups are read with one ``numpy.frombuffer`` each, with a dtype built from the
group's fields (``WIRE``: guide 6.2, MSB first).

Rules: ``split`` never raises on bad bytes; it returns None where it cannot cut (no plain group longer than
``keep``, a count or a length past the end, a layout it does not know) and the caller decodes the whole telegram,
so a malformed telegram meets the codec's own error.
"""

from __future__ import annotations

import functools
import struct
from dataclasses import dataclass

import numpy as np

from pltf.spec.compiler import LENGTH, WIRE, allowed_values, fixed_size, value_range
from pltf.spec.model import Direction, FieldDef, load_telegrams


@dataclass(frozen=True)
class Column:
    """A group of a telegram as a numpy structured array (one field per item field), and its full count."""

    name: str
    items: np.ndarray


@functools.cache
def item_dtype(group: FieldDef) -> np.dtype | None:
    """The wire layout of one item of a plain group (None when the group is not plain)."""
    plain = all(
        fixed_size(f) is not None and not f.repeat and f.const is None and allowed_values(f) is None
        for f in group.fields
    )
    if not plain or any(value_range(f) is not None for f in group.fields):
        return None
    return np.dtype([(f.name, ">" + WIRE[f.type][0]) for f in group.fields])


@functools.cache
def _item_size(group: FieldDef) -> int | None:
    sizes = [fixed_size(f) for f in group.fields]
    return None if None in sizes else sum(n for n in sizes if n is not None)


Step = tuple[int, FieldDef | None, "np.dtype | None", int]  # (fixed bytes before, field, plain dtype, item size)


def _steps(layout: tuple[FieldDef, ...]) -> tuple[Step, ...] | None:
    """The layout as runs of fixed bytes each followed by a counted field (a string or a group), and the fixed
    bytes after the last (field None); None when a group's items vary in size."""
    steps: list[Step] = []
    fixed = 0
    for f in layout:
        size = fixed_size(f)
        if size is not None:
            fixed += size
            continue
        width = _item_size(f) if f.is_group else 1
        if width is None:
            return None
        steps.append((fixed, f, item_dtype(f) if f.is_group else None, width))
        fixed = 0
    steps.append((fixed, None, None, 0))
    return tuple(steps)


@functools.cache
def _layouts(direction: Direction) -> dict[int, tuple[Step, ...] | None]:
    return {t.id: _steps(lay) for t in load_telegrams() if t.layout_known and (lay := t.layout(direction)) is not None}


def split(direction: Direction, data: bytes, keep: int) -> tuple[bytes, list[Column]] | None:
    """(the telegram ``data`` (identifier first) with each plain group longer than ``keep`` cut to ``keep`` items,
    the cut groups as columns, whole) or None."""
    steps = _layouts(direction).get(data[0]) if data else None
    if steps is None:
        return None
    pos, end, parts, columns, last = 1, len(data), [], [], 0
    try:
        for fixed, f, dtype, width in steps:
            pos += fixed
            if f is None:
                break
            n = LENGTH.unpack_from(data, pos)[0]
            pos += LENGTH.size
            if n < 0 or n * width > end - pos:
                return None
            if dtype is not None and n > keep:
                columns.append(Column(f.name, np.frombuffer(data, dtype, count=n, offset=pos)))
                parts += [data[last : pos - LENGTH.size], LENGTH.pack(keep), data[pos : pos + keep * width]]
                last = pos + n * width
            pos += n * width
    except struct.error:
        return None
    if not columns:
        return None
    parts.append(data[last:])
    return b"".join(parts), columns
