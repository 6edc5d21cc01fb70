"""Log the platform's status and battery to CSV, one row per interval, across lost connections.

    python examples/monitor.py --target 127.0.0.1:10002 --interval 1 --out status.csv

Columns: ``time`` (this computer's clock, ISO 8601), ``platform_ms`` (the status time stamp), ``state``,
``mode``, ``emergency``, ``x_mm``, ``y_mm``, ``angle_deg`` (the estimated pose), ``target_reached`` (0/1),
``planner``, ``battery_mv``. Each row is flushed as it is written (``tail -f`` works). Only CMD_GET_STATUS is
sent: the monitor never changes the platform, so it can run beside the application that drives it (on the
other port, guide 6.1: one client per port).

When the connection cannot be made or is lost (the platform restarts, the port is taken), a line goes to
standard error and the monitor tries again every ``--retry`` seconds; rows go on when it is back. Exit status 0
after ``--count`` rows (default: until Ctrl-C), 2 for bad arguments or an unwritable file.
"""

from __future__ import annotations

import argparse
import csv
import datetime
import sys
import time
from typing import TextIO

from pltf.client import ConnectionClosed, PlatformClient, PlatformError, Status, Timeout

COLUMNS = [
    "time",
    "platform_ms",
    "state",
    "mode",
    "emergency",
    "x_mm",
    "y_mm",
    "angle_deg",
    "target_reached",
    "planner",
    "battery_mv",
]


def target(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise argparse.ArgumentTypeError(f"expected HOST:PORT, got {text!r}")
    return host.strip("[]"), int(port)


def row(status: Status) -> list[object]:
    x, y, angle = status.pose
    return [
        datetime.datetime.now().isoformat(timespec="milliseconds"),
        status.timestamp_ms,
        status.operation_state.name,
        status.motion_mode.name,
        status.emergency_state.name,
        f"{x:.0f}",
        f"{y:.0f}",
        f"{angle:.2f}",
        int(status.target_reached),
        status.planner_state.name,
        status.io_battery_voltage_mv,
    ]


def monitor(args: argparse.Namespace, out: TextIO) -> int:
    host, port = args.target
    writer = csv.writer(out)
    writer.writerow(COLUMNS)
    out.flush()
    written = 0
    while args.count == 0 or written < args.count:
        try:
            with PlatformClient(host, port, timeout=max(2.0, 2 * args.interval)) as pltf:
                while args.count == 0 or written < args.count:
                    started = time.monotonic()
                    writer.writerow(row(pltf.get_status()))
                    out.flush()
                    written += 1
                    if args.count == 0 or written < args.count:
                        time.sleep(max(0.0, args.interval - (time.monotonic() - started)))
        except (ConnectionClosed, Timeout) as exc:
            print(f"monitor: {host}:{port}: {exc}; retrying in {args.retry:g} s", file=sys.stderr, flush=True)
            time.sleep(args.retry)
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--target", type=target, default=("127.0.0.1", 10000), help="HOST:PORT of PlatformCtrl")
    parser.add_argument("--interval", type=float, default=1.0, help="seconds between two rows (default 1)")
    parser.add_argument("--count", type=int, default=0, help="rows to write, then stop (default 0: until Ctrl-C)")
    parser.add_argument("--out", default="-", help="CSV file to write (default -: standard output)")
    parser.add_argument("--retry", type=float, default=2.0, help="seconds between two connection attempts")
    args = parser.parse_args(argv)
    if args.interval < 0 or args.count < 0 or args.retry <= 0:
        parser.error("--interval and --count must be >= 0, --retry > 0")
    try:
        out = sys.stdout if args.out == "-" else open(args.out, "w", newline="", encoding="utf-8")  # noqa: SIM115
    except OSError as exc:
        print(f"monitor: error: {args.out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    try:
        return monitor(args, out)
    except PlatformError as exc:  # a protocol error: not a platform this monitor can read
        print(f"monitor: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 0
    finally:
        if out is not sys.stdout:
            out.close()


if __name__ == "__main__":
    sys.exit(main())
