# Typing of the C extension built from _raycast.c (see raycast.py).
from typing_extensions import Buffer

def fan(
    x: float, y: float, a0: float, heading: float, step: float, max_range: float, count: int,
    segs: Buffer, circs: Buffer, cos_b: Buffer, sin_b: Buffer, ranges: Buffer, hits: Buffer,
) -> None: ...
def rays(
    ox: Buffer, oy: Buffer, dx: Buffer, dy: Buffer, segs: Buffer, circs: Buffer, max_range: float,
    ranges: Buffer, hits: Buffer,
) -> None: ...
