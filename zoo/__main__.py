"""``python -m pltf.zoo MEMBER (--serve reference|emulator | --upstream HOST:PORT,PORT) [options]``: run one zoo
member in front of a PlatformCtrl target; ``--list`` shows the members.

With ``--serve`` the member starts the target behind it itself (ephemeral ports, stopped with the member);
``--upstream`` puts it in front of a target that runs already. It logs ``zoo MEMBER: server started at port N``
once per port, in port order (the line every launcher of the toolkit reads), ending `` on HOST`` when it listens
elsewhere than 127.0.0.1. Exit status: 2 for bad arguments or a target that cannot be started, 134 when a
planted crash fires, 3 after a planted hang.
"""

from __future__ import annotations

import argparse
import asyncio
import dataclasses
import json
import signal
import sys
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from pltf.harness import launch
from pltf.zoo.bugs import BUGS, Leak
from pltf.zoo.members import GET_STATUS_ID, MEMBERS, Member, member
from pltf.zoo.relay import Relay
from pltf.zoo.schedule import for_ident, jitter
from pltf.zoo.values import STYLES

RETIRE_WAIT = 15.0  # s a restart or the exit waits for the old target's stop


def _pair(text: str, what: str, cast: type = int) -> tuple[float, float]:
    try:
        lo, hi = (cast(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what} as LOW,HIGH, got {text!r}") from None
    if not 0 <= lo <= hi:
        raise argparse.ArgumentTypeError(f"expected 0 <= LOW <= HIGH, got {text!r}")
    return lo, hi


def _ports(text: str) -> tuple[int, int]:
    parts = text.split(",")
    if len(parts) != 2 or not all(p.strip().isdigit() and int(p) < 65536 for p in parts):
        raise argparse.ArgumentTypeError(f"expected two ports A,B (0: any free port), got {text!r}")
    return int(parts[0]), int(parts[1])


def _upstream(text: str) -> tuple[str, tuple[int, int]]:
    host, sep, ports = text.rpartition(":")
    if not sep or not host:
        raise argparse.ArgumentTypeError(f"expected HOST:PORT,PORT, got {text!r}")
    a, b = _ports(ports)
    if not (a and b):
        raise argparse.ArgumentTypeError(f"expected two upstream ports, got {text!r}")
    return host, (a, b)


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m pltf.zoo",
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="members:\n" + "\n".join(f"  {m.name:20} {m.summary}" for m in MEMBERS.values()),
    )
    p.add_argument("member", nargs="?", help="the member to run (--list shows them)")
    p.add_argument("--list", action="store_true", help="list the members and exit")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--serve", choices=("reference", "emulator"), help="start this target behind the member")
    where.add_argument("--upstream", type=_upstream, metavar="HOST:PORT,PORT", help="a target that runs already")
    p.add_argument("--host", help="address to listen on (default 127.0.0.1; ipv6-only: ::1)")
    p.add_argument("--ports", type=_ports, default=(0, 0), metavar="A,B", help="ports to listen on (default 0,0: any)")
    p.add_argument("--seed", type=int, default=1, help="seed of the member's random delays (and of --serve's target)")
    p.add_argument("--time-scale", type=float, default=1.0, metavar="X", help="time scale of the --serve target")
    p.add_argument(
        "--release-ms",
        type=lambda t: _pair(t, "milliseconds"),
        metavar="LO,HI",
        help="turn-away members: the port is free LO-HI ms after its client left",
    )
    p.add_argument(
        "--turn-away",
        choices=("fin", "rst", "refuse"),
        help="turn-away members: close a newcomer with FIN or RST, or refuse it (the port stops listening)",
    )
    p.add_argument("--bug", choices=sorted(BUGS), help="plant this bug in the member (replaces its own)")
    p.add_argument(
        "--delay-ms",
        type=lambda t: _pair(t, "milliseconds"),
        metavar="LO,HI",
        help="every reply LO-HI ms late (jitter)",
    )
    p.add_argument(
        "--accept-every-ms",
        type=float,
        metavar="MS",
        help="accept on a timer: every MS ms, every newcomer waiting in the backlog (slow-accept: 100)",
    )
    p.add_argument(
        "--absurd",
        choices=sorted(STYLES),
        help="rewrite the doubles of GET_POSITION and GET_STATUS: little-endian byte order, NaN or infinity",
    )
    p.add_argument("--idle-seconds", type=float, metavar="S", help="close a client silent for S seconds (idle-drop)")
    p.add_argument(
        "--restart-every", type=float, metavar="S", help="restart every S seconds, the ports gone for 2 s (restarts)"
    )
    p.add_argument("--segment", type=int, metavar="N", help="cut the replies into writes of 1..N bytes")
    p.add_argument("--status-delay", type=float, metavar="S", help="every CMD_GET_STATUS reply S seconds late")
    p.add_argument("--leak-kb", type=int, metavar="K", help="leak: KiB leaked per request (default 32)")
    p.add_argument("--leak-limit-mb", type=int, metavar="M", help="leak: the target dies at M MiB (default 64)")
    p.add_argument(
        "--hang-seconds",
        type=float,
        default=600.0,
        metavar="S",
        help="a planted hang lasts S seconds, then the member exits (default 600)",
    )
    p.add_argument(
        "--log-level",
        default="INFO",
        choices=("DEBUG", "INFO", "WARNING", "ERROR"),
        help="log level of the --serve reference server (default INFO; the benchmarks use ERROR)",
    )
    p.add_argument("--stats", metavar="FILE", help="write the clients served and turned away per port here at exit")
    return p


def configured(args: argparse.Namespace) -> Member:
    """The member with the options given on the command line."""
    m = member(args.member)
    changes: dict[str, object] = {}
    if args.release_ms is not None:
        changes["release"] = (args.release_ms[0] / 1000, args.release_ms[1] / 1000)
    if args.turn_away is not None:
        changes["turn_away"] = args.turn_away
    if args.delay_ms is not None:
        changes["delay"] = jitter(args.delay_ms[0] / 1000, args.delay_ms[1] / 1000)
    if args.accept_every_ms is not None:
        changes["accept_every"] = max(0.0, args.accept_every_ms / 1000)
    if args.absurd is not None:
        changes["absurd"] = args.absurd
    if args.idle_seconds is not None:
        changes["idle_drop"] = max(0.0, args.idle_seconds)
    if args.restart_every is not None:
        changes["restart_every"] = max(0.0, args.restart_every)
    if args.segment is not None:
        changes["segment"] = max(0, args.segment)
    if args.status_delay is not None:
        changes["delay"] = for_ident(GET_STATUS_ID, args.status_delay)
    if args.bug is not None:
        changes["bug"] = BUGS[args.bug]
    if args.leak_kb is not None or args.leak_limit_mb is not None:
        kb, limit = args.leak_kb or 32, args.leak_limit_mb or 64
        changes["bug"] = lambda: Leak(kb=kb, limit_mb=limit)
    return dataclasses.replace(m, **changes) if changes else m  # type: ignore[arg-type]


def _error(message: str) -> NoReturn:
    print(f"python -m pltf.zoo: error: {message}", file=sys.stderr)
    raise SystemExit(2)


def _terminate(signum: int, frame: object) -> NoReturn:
    raise SystemExit(128 + signum)  # interrupts even a planted hang; the finally clauses stop the target


def main(argv: Sequence[str] | None = None) -> int:
    args = parser().parse_args(argv)
    if args.list:
        for m in MEMBERS.values():
            print(
                f"{m.name:18} {'conforming (' + m.profile + ')' if m.conforming else 'fails the suite':22} {m.summary}"
            )
        return 0
    _check(args)
    m = configured(args)
    signal.signal(signal.SIGTERM, _terminate)
    behind: launch.Launched | None = None
    targets: Spare | None = None
    relay: Relay | None = None
    try:
        if args.serve:
            behind = _start_behind(args)
            host, ports = "127.0.0.1", behind.ports
            print(f"zoo {m.name}: {behind.name} behind at {host}:{ports[0]},{ports[1]} (pid {behind.pid})", flush=True)
        else:
            host, ports = args.upstream
        targets = Spare(args, behind, m.restart_every > 0)
        relay = Relay(
            m,
            host,
            list(ports),
            host=args.host or m.host,
            ports=args.ports,
            seed=args.seed,
            hang_seconds=args.hang_seconds,
            on_exit=targets.cleanup,
            on_restart=targets.restart,
            log=lambda line: print(line, flush=True),
        )
        _serve(relay, m.name, args.host or m.host)
        return 0
    finally:
        if args.stats and relay is not None:
            Path(args.stats).write_text(json.dumps(relay.stats))
        if targets is not None:
            targets.cleanup()
        elif behind is not None:
            behind.cleanup()


def _check(args: argparse.Namespace) -> None:
    """The member and what it stands in front of: one line on stderr and exit 2 when missing."""
    if not args.member:
        _error("name a member (--list shows them)")
    if args.member not in MEMBERS:
        _error(f"no member {args.member!r} (members: {', '.join(MEMBERS)})")
    if not (args.serve or args.upstream):
        _error("give --serve reference|emulator or --upstream HOST:PORT,PORT")


def _start_behind(args: argparse.Namespace) -> launch.Launched:
    """The implementation behind the member, started in our process group (stopped with us)."""
    behind: launch.Launched | None = None
    try:
        level = {"log_level": args.log_level} if args.serve == "reference" else {}
        behind = launch.target(args.serve, time_scale=args.time_scale, seed=args.seed, **level)
        behind.new_session = False
        behind.start()
    except launch.LaunchError as exc:
        if behind is not None:
            behind.cleanup()
        _error(str(exc))
    return behind


class Spare:
    """A fresh target behind a member that restarts, started ahead (spawned at once, its ports read at the
    restart): a restart then takes the member's ``restart_down``, not a start-up of the target, however loaded the
    machine is. The next spare is spawned at the restart, in the caller's thread (the relay's executor, which lives
    as long as the member: a target dies with the thread that started it, launch._pdeathsig); the old target is
    stopped in a thread of its own, so its exit (SIGTERM, up to a 3 s grace) does not keep the ports gone (it did:
    3.5-4.8 s instead of 2 behind the reference server at --restart-every 5). With --upstream there is nothing to
    restart (the member only drops its connections and ports)."""

    def __init__(self, args: argparse.Namespace, behind: launch.Launched | None, restarts: bool) -> None:
        self.args, self.current = args, behind
        self.spare = self._spawn() if behind is not None and restarts else None
        self._stopping: threading.Thread | None = None

    def _spawn(self) -> launch.Launched:
        level = {"log_level": self.args.log_level} if self.args.serve == "reference" else {}
        spare = launch.target(self.args.serve, time_scale=self.args.time_scale, seed=self.args.seed, **level)
        spare.new_session = False
        spare.begin()
        return spare

    def restart(self) -> Sequence[int]:
        """The fresh target's ports (the old one is stopped: its state is lost); () with --upstream."""
        if self.current is None:
            return ()
        self._settled()
        old, fresh = self.current, self.spare
        try:
            ports = fresh.ports_when_ready() if fresh is not None else old.start()
        except launch.LaunchError:  # the spare did not come up: start one now
            ports, fresh = old.start(), None
        if fresh is not None:
            self.current = fresh
            self._stopping = threading.Thread(target=old.cleanup, daemon=True)
            self._stopping.start()
        self.spare = self._spawn()
        return ports

    def _settled(self) -> None:
        """The old target's stop is over (a restart or the exit waits for it, at most ``RETIRE_WAIT`` s)."""
        if self._stopping is not None:
            self._stopping.join(RETIRE_WAIT)
            self._stopping = None

    def cleanup(self) -> None:
        self._settled()
        for target in (self.current, self.spare):
            if target is not None:
                target.cleanup()


def _serve(relay: Relay, name: str, listen_host: str) -> None:
    where = "" if listen_host == "127.0.0.1" else f" on {listen_host}"  # harness.launch talks to that address

    def ready(bound: list[int]) -> None:
        for port in bound:
            print(f"zoo {name}: server started at port {port}{where}", flush=True)

    try:
        asyncio.run(relay.serve_forever(ready))
    except OSError as exc:
        _error(f"cannot listen on {listen_host}: {exc}")
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    sys.exit(main())
