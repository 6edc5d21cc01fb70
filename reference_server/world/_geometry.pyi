# Typing of the C extension built from _geometry.c (see geometry.py): float64 / bool arrays, C-contiguous.
from typing import Any

import numpy.typing as npt

_A = npt.NDArray[Any]

def segments_clear(q: _A, segs: _A, circ: _A, rad: _A, ok: _A) -> None: ...
