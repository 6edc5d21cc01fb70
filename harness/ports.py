"""Free TCP ports on the loopback, for a target that must be given its ports (one that does not log them).

Rules: a port is free at the moment of asking (bound to port 0 and released), not reserved: another process may
take it before the target binds it. Prefer port 0 and the target's ``server started at port N`` lines
(harness/launch.py) wherever the target logs them.
"""

from __future__ import annotations

import socket

HOST = "127.0.0.1"


def free_ports() -> tuple[int, int]:
    """Two ports free at the moment of asking (bound to port 0 and released)."""
    socks = [socket.socket() for _ in range(2)]
    try:
        for s in socks:
            s.bind((HOST, 0))
        return socks[0].getsockname()[1], socks[1].getsockname()[1]
    finally:
        for s in socks:
            s.close()
