"""The soak's reconnecting client: every few seconds a new connection, one GET_POSITION, close.

    python -m benchmarks.soak.reconnect --target 127.0.0.1:PORT --every 3

What the platform does with it is what a user sees, counted by outcome: ``served`` (the reply came), or the
client library's error (turned away with FIN, a reset, no reply in time). On SIGTERM it prints one line,
``reconnect: N connections: served=A ...``, and exits 0.
"""

from __future__ import annotations

import argparse
import collections
import signal
import sys
import threading

from pltf.client import PlatformClient, PlatformError


def once(host: str, port: int, timeout: float) -> str:
    try:
        with PlatformClient(host, port, timeout=timeout) as pltf:
            pltf.get_position()
    except PlatformError as exc:
        return type(exc).__name__
    return "served"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--target", required=True, help="HOST:PORT")
    parser.add_argument("--every", type=float, default=3.0, help="seconds between connections (default 3)")
    parser.add_argument("--timeout", type=float, default=2.0, help="seconds to wait for the reply (default 2)")
    args = parser.parse_args(argv)
    host, _, port = args.target.rpartition(":")
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    outcomes: collections.Counter[str] = collections.Counter()
    while not stop.is_set():
        outcomes[once(host.strip("[]"), int(port), args.timeout)] += 1
        print(f"reconnect: {sum(outcomes.values())} {dict(outcomes)}", flush=True)
        stop.wait(args.every)
    counts = " ".join(f"{k}={v}" for k, v in sorted(outcomes.items()))
    print(f"reconnect: {sum(outcomes.values())} connections: {counts}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
