"""Drive the platform from the keyboard with velocities (motion mode Velocity, guide 4.3).

    python examples/teleop.py --target 127.0.0.1:10002

Keys: w / arrow up: forward, s / arrow down: backward, a / arrow left and d / arrow right: turn on the spot,
space: stop, q: quit (the platform is stopped and left in state Ready).

A terminal sends no key-up event: a key counts as held while it repeats, and as released when no repeat came for
``--release-ms`` (set it above your keyboard's repeat interval; keep it below the watchdog). While a key is held,
CMD_MOVE_VEL is sent again every third of VelWatchdogTime, so the platform's watchdog (guide 4.3: "The platform
keeps the last set velocity until a new velocity value is set or a watchdog time expired") never stops it under
the driver's finger; on release a zero velocity is sent at once, not left to the watchdog. Standard input may be
a terminal (read key by key) or a pipe: the same bytes drive.

Lines on standard output: ``ready ...``, ``drive v=.. w=..`` when the velocity changes, ``stop (released)`` or
``stop (space)``, ``bye``. ``--time-scale`` is the target's simulated seconds per wall second (a reference server
run faster than real time), so the refresh keeps pace with its watchdog.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import select
import sys
import termios
import time
import tty
from collections.abc import Iterator

from pltf.client import MotionMode, OperationState, PlatformClient, PlatformError

READY, RUNNING = OperationState.ST_OP_READY, OperationState.ST_OP_RUNNING
# key -> (translation sign, rotation sign); arrows arrive as ESC [ A..D
KEYS = {
    "w": (1, 0),
    "s": (-1, 0),
    "a": (0, 1),
    "d": (0, -1),
    "\x1b[A": (1, 0),
    "\x1b[B": (-1, 0),
    "\x1b[D": (0, 1),
    "\x1b[C": (0, -1),
}


def target(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise argparse.ArgumentTypeError(f"expected HOST:PORT, got {text!r}")
    return host.strip("[]"), int(port)


def keys_of(data: str) -> Iterator[str]:
    """The keys in a chunk read from the terminal: single characters and arrow escape sequences."""
    i = 0
    while i < len(data):
        if data.startswith("\x1b[", i) and i + 2 < len(data):
            yield data[i : i + 3]
            i += 3
        else:
            yield data[i]
            i += 1


@contextlib.contextmanager
def keyboard(fd: int) -> Iterator[None]:
    """The terminal in cbreak mode (keys arrive one by one, not echoed) until the end; a pipe as it is."""
    if not os.isatty(fd):
        yield
        return
    saved = termios.tcgetattr(fd)
    try:
        tty.setcbreak(fd)
        yield
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)


def velocity_mode(pltf: PlatformClient) -> None:
    """Bring the platform up and to state Running in mode Velocity (the mode only changes in Ready)."""
    status = pltf.bring_up(timeout=30)
    if status.motion_mode != MotionMode.MODE_MOTION_VEL:
        if status.operation_state != READY:
            pltf.stop()
            pltf.wait_state(READY)
        pltf.set_mode(MotionMode.MODE_MOTION_VEL)
        pltf.wait_mode(MotionMode.MODE_MOTION_VEL)
    if pltf.get_status().operation_state != RUNNING:
        pltf.start()
        pltf.wait_state(RUNNING)


class Teleop:
    """The key state and what to send: a velocity while a key is held, refreshed; zero at once on release."""

    def __init__(self, pltf: PlatformClient, args: argparse.Namespace, refresh: float) -> None:
        self.pltf = pltf
        self.speed: int = args.speed
        self.turn: int = args.turn
        self.release = float(args.release_ms) / 1000.0
        self.refresh = refresh
        self.want = (0, 0)  # (mm/s, mrad/s)
        self.last_key = 0.0
        self.last_sent = 0.0

    def key(self, key: str, now: float) -> bool:
        """One key; False to quit."""
        if key == "q":
            return False
        if key == " ":
            self.set((0, 0), now, "stop (space)")
        elif key in KEYS:
            trans, rot = KEYS[key]
            self.last_key = now
            self.set((trans * self.speed, rot * self.turn), now, None)
        return True

    def set(self, want: tuple[int, int], now: float, why: str | None) -> None:
        if want != self.want:
            self.want = want
            print(why or f"drive v={want[0]} w={want[1]}", flush=True)
            self.send(now)

    def send(self, now: float) -> None:
        # guide 6.3 CMD_MOVE_VEL: translation [mm/s], rotation [1000*rad/s] (toolkit erratum E-REP-005)
        self.pltf.move_vel(vel_trans_mm_s=self.want[0], vel_rot_mrad_s=self.want[1])
        self.last_sent = now

    def tick(self, now: float) -> float:
        """Release and refresh when due; the seconds until the next thing is due."""
        if self.want == (0, 0):
            return self.refresh
        if now - self.last_key >= self.release:
            self.set((0, 0), now, "stop (released)")
            return self.refresh
        if now - self.last_sent >= self.refresh:
            self.send(now)
        return max(0.0, min(self.last_sent + self.refresh, self.last_key + self.release) - now)


def drive(pltf: PlatformClient, args: argparse.Namespace) -> int:
    velocity_mode(pltf)
    watchdog_ms = float(pltf.get_pltf_param("VelWatchdogTime").typed_value)
    refresh = watchdog_ms / 3000.0 / args.time_scale  # wall seconds between two CMD_MOVE_VEL while a key is held
    teleop = Teleop(pltf, args, refresh)
    fd = sys.stdin.fileno()
    print(
        f"ready: w/a/s/d or arrows drive, space stops, q quits (watchdog {watchdog_ms:g} ms, refresh "
        f"{refresh * 1000:.0f} ms)",
        flush=True,
    )
    try:
        with keyboard(fd):
            running = True
            while running:
                wait = teleop.tick(time.monotonic())
                readable, _, _ = select.select([fd], [], [], wait)
                if not readable:
                    continue
                data = os.read(fd, 64).decode("latin-1")
                running = bool(data)  # end of input: quit like q
                for key in keys_of(data):
                    running = running and teleop.key(key, time.monotonic())
    finally:  # q, end of input, Ctrl-C: the platform does not wait for its watchdog
        with contextlib.suppress(PlatformError):
            teleop.set((0, 0), time.monotonic(), "stop (quit)")
            pltf.stop()
            pltf.wait_state(READY)
    print("bye", flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--target", type=target, default=("127.0.0.1", 10002), help="HOST:PORT of PlatformCtrl")
    parser.add_argument("--speed", type=int, default=300, help="translation while a key is held, mm/s (default 300)")
    parser.add_argument("--turn", type=int, default=600, help="rotation while a key is held, mrad/s (default 600)")
    parser.add_argument(
        "--release-ms", type=float, default=250.0, help="no key repeat for this long means released (default 250 ms)"
    )
    parser.add_argument(
        "--time-scale",
        type=float,
        default=1.0,
        help="the target's simulated seconds per wall second (default 1: a real platform)",
    )
    args = parser.parse_args(argv)
    if not args.time_scale > 0 or not args.release_ms > 0:
        parser.error("--time-scale and --release-ms must be > 0")
    host, port = args.target
    try:
        with PlatformClient(host, port, timeout=10.0) as pltf:
            return drive(pltf, args)
    except PlatformError as exc:
        print(f"teleop: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
