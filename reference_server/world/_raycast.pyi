# Typing of the C extension built from _raycast.c (see raycast.py): float64 / int64 arrays, C-contiguous.
from typing import Any

import numpy.typing as npt

_A = npt.NDArray[Any]

def fan(
    x: float,
    y: float,
    a0: float,
    heading: float,
    step: float,
    max_range: float,
    count: int,
    segs: _A,
    circs: _A,
    cos_b: _A,
    sin_b: _A,
    ranges: _A,
    hits: _A,
) -> None: ...
def rays(ox: _A, oy: _A, dx: _A, dy: _A, segs: _A, circs: _A, max_range: float, ranges: _A, hits: _A) -> None: ...
