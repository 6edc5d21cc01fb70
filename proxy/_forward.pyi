# Typing of the C extension built from _forward.c (see network.py): the forwarding loop of one connection.
from collections.abc import Callable

def run(
    client_fd: int,
    target_fd: int,
    wake_fd: int,
    spin_us: int,
    on_data: Callable[[list[tuple[bool, float, bytes]]], object],
    on_eof: Callable[[bool], bool],
) -> tuple[bool, int] | None: ...
