# Typing of the C extension built from _draw.c (see draw.py, its only caller).
from typing import Any

def setup(
    telegrams: list[tuple[Any, ...]],
    close_socket: int,
    strings: tuple[bytes, ...],
    origins: tuple[str, ...],
    case: type,
    deliveries: tuple[Any, ...],
    expects: tuple[str, str, str],
    get_status: bytes,
    big: tuple[bytes, bytes],
) -> None: ...
def block(
    seed: int,
    number: int,
    n: int,
    mask: bytes,
    picks: bytes,
    pick_cum: bytes,
    free_ids: bytes,
    gen_cum: bytes,
    mut_cum: bytes,
    keys: list[bytes],
    stations: list[bytes],
    pose: tuple[int, int, int],
    pool: bool,
    big_share: float,
) -> tuple[list[Any], int]: ...
def survey(data: bytes) -> tuple[str, tuple[int, ...]] | None: ...
def forbidden(data: bytes, mask: bytes) -> bool: ...
