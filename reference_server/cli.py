"""Command line of the reference server: ``python -m pltf.reference_server`` and ``pltf serve`` share it.

Rules: options are parsed here, the data dir is opened (and seeded from the repository's fixtures when it is
empty), then reference_server.network runs until CMD_EXIT or a signal. User errors print one line on stderr
and exit 2. The fake hardware (reference_server/hardware_link.py) is on unless ``--no-hardware``; the fault-control
channel (reference_server/control.py) listens on 127.0.0.1 only when ``--control-port`` is given, started through
network's ``ready`` callback.
"""

from __future__ import annotations

import argparse
import gc
import logging
import sys
from collections.abc import Callable, Sequence

from pltf.reference_server import hardware_link, network
from pltf.reference_server.control import start_control
from pltf.reference_server.kinematics import Drive
from pltf.reference_server.motion_api import MotionFactory
from pltf.reference_server.platform import Platform
from pltf.reference_server.storage import Storage
from pltf.reference_server.tasks.local import factory as program_factory
from pltf.reference_server.world.model import factory as world_factory

LOG_FORMAT = "%(asctime)s.%(msecs)03d %(levelname)-7s %(message)s"
LOG_DATE = "%Y-%m-%d %H:%M:%S"
DEFAULT_PORTS = (10000, 10002)  # guide 6.1: "listens for clients on the socket ports 10000 and 10002"

log = logging.getLogger("pltf.server")


def _ideal(seed: int) -> MotionFactory:
    return Drive


MOTION: dict[str, Callable[[int], MotionFactory]] = {"world": world_factory, "ideal": _ideal}


def _numbers(text: str) -> list[int]:
    try:
        ports = [int(part) for part in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated port numbers, got {text!r}") from None
    if any(not 0 <= p <= 65535 for p in ports):
        raise argparse.ArgumentTypeError(f"ports must be 0..65535 (0: any free port), got {text!r}")
    return ports


def parse_ports(text: str) -> list[int]:
    """``--ports``: the guide's two ports (6.1), or one: a platform with a single socket."""
    ports = _numbers(text)
    if len(ports) not in (1, 2):
        raise argparse.ArgumentTypeError(f"expected one or two ports (PORT[,PORT]), got {text!r}")
    return ports


def parse_port(text: str) -> int:
    ports = _numbers(text)
    if len(ports) != 1:
        raise argparse.ArgumentTypeError(f"expected one port number, got {text!r}")
    return ports[0]


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    p.add_argument(
        "--ports",
        type=parse_ports,
        default=list(DEFAULT_PORTS),
        metavar="PORT[,PORT]",
        help="the two ports (guide 6.1: 10000,10002, the default), each serving the full command set to one "
        "client at a time; one port: only that one is served (tools that need a second port, such as conform "
        "--second-port and fuzz's liveness probe, then have none); 0 = any free port, printed at start",
    )
    p.add_argument("--data-dir", default="data", help="the platform's hard disk; seeded from fixtures/ when empty")
    p.add_argument(
        "--time-scale",
        type=positive_float,
        default=1.0,
        help="simulated seconds per wall second (default 1)",
    )
    p.add_argument(
        "--motion",
        choices=sorted(MOTION),
        default="world",
        help="motion model: world (pymunk body, laser, localization, planner; default) or ideal (wheels only)",
    )
    p.add_argument(
        "--no-hardware",
        action="store_true",
        help="no fake hardware: ideal wheels, no CAN boards (every board ABSENT), no laser scanner",
    )
    p.add_argument(
        "--can-interface",
        default="virtual",
        help="python-can interface of the fake boards (default virtual: in-process; socketcan for vcan0)",
    )
    p.add_argument(
        "--can-channel",
        default=None,
        help="CAN channel (default: a virtual channel of this server's own; e.g. vcan0 with socketcan)",
    )
    p.add_argument(
        "--control-port",
        type=parse_port,
        default=None,
        help="TCP port of the fault-control channel on 127.0.0.1 (0 = any free port; default: off)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the simulation's random numbers (default 0)")
    p.add_argument(
        "--fleet",
        default=None,
        metavar="FILE|N",
        help="serve a fleet in one world: a fleet file (YAML: platforms with name, ports, pose, ...) or N platforms "
        "at free places of the map on ports A+4k,B+4k from --ports A,B; data dirs DATA_DIR/NAME",
    )
    p.add_argument(
        "--ray",
        default=None,
        metavar="ADDRESS|auto",
        help="with --fleet: serve the fleet as shards on a Ray cluster (one shard per node; a platform's 'node' "
        "in the file picks its node, else round-robin); needs the ray extra",
    )
    p.add_argument(
        "--processes",
        type=int,
        default=None,
        metavar="K",
        help="with --fleet: split the fleet over K processes of this machine (one shard each; a platform's 'node' "
        "in the file picks its process, else round-robin): a fleet too big for one core uses the others",
    )
    p.add_argument(
        "--ray-lag",
        type=int,
        default=1,
        metavar="N",
        help="with --ray or --processes: at each tick a shard sees the other shards' platforms where they were N "
        "periods before (default 1: lockstep one period behind)",
    )
    p.add_argument(
        "--shared-map",
        action="store_true",
        help="with --fleet: a CMD_SET_MAP one platform accepts is sent to every other one too",
    )
    p.add_argument(
        "--log-level",
        default="INFO",
        choices=["DEBUG", "INFO", "WARNING", "ERROR"],
        help="log level (default INFO)",
    )


def build_platform(
    storage: Storage,
    seed: int,
    *,
    motion: str = "world",
    hardware: bool = True,
    can_interface: str = "virtual",
    can_channel: str | None = None,
) -> Platform:
    """The platform ``pltf serve`` runs (its defaults: the world, the fake hardware, the task interpreter); the
    conformance suite's in-process reference builds the same one."""
    link = hardware_link.factory(can_interface, can_channel) if hardware else None
    return Platform(storage, seed=seed, motion=MOTION[motion](seed), program=program_factory, hardware=link)


def run(args: argparse.Namespace, prog: str = "pltf serve") -> int:
    """Serve until CMD_EXIT or a signal; a user error is one line ``PROG: error: ...`` on stderr and status 2."""
    logging.basicConfig(level=args.log_level, format=LOG_FORMAT, datefmt=LOG_DATE, stream=sys.stderr, force=True)
    if getattr(args, "fleet", None) is not None:
        from pltf.reference_server.fleet.cli import run as run_fleet

        return run_fleet(args, prog)
    for option in ("shared_map", "ray", "processes"):
        if getattr(args, option, None):
            print(f"{prog}: error: --{option.replace('_', '-')} needs --fleet", file=sys.stderr)
            return 2
    try:
        storage = Storage(args.data_dir)
    except OSError as exc:
        print(f"{prog}: error: data dir {args.data_dir}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    seeded = storage.seed_from_fixtures()
    if seeded:
        log.info("data dir %s was empty: seeded %d files from fixtures", storage.root, len(seeded))
    if args.no_hardware and args.control_port is not None:
        print(f"{prog}: error: --control-port needs the fake hardware (drop --no-hardware)", file=sys.stderr)
        return 2
    try:
        platform = build_platform(
            storage,
            args.seed,
            motion=args.motion,
            hardware=not args.no_hardware,
            can_interface=args.can_interface,
            can_channel=args.can_channel,
        )
    except (OSError, ValueError, ImportError) as exc:  # python-can: an unknown interface, a missing channel
        print(f"{prog}: error: CAN interface {args.can_interface} {args.can_channel or ''}: {exc}", file=sys.stderr)
        return 2
    options: dict[str, object] = {}
    if args.control_port is not None:
        options["ready"] = start_control(platform, args.control_port)
    # This process is the server: what exists now (modules, the spec's telegram classes, the CAN database, the
    # platform) lives as long as it does, so the collector stops scanning it: its full collections walked those
    # ~75,000 objects again and again (measured with benchmarks.bench_motion's platform run: real-time factor
    # 42-57 over 8 runs with the walk, 55-59 over 10 without).
    gc.collect()
    gc.freeze()
    try:
        return network.run(platform, args.host, args.ports, args.time_scale, **options)
    except OSError as exc:
        print(f"{prog}: error: cannot listen on {args.host} {args.ports}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # a signal before the handlers were installed
        return 0
    finally:
        platform.close()


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m pltf.reference_server", description="PlatformCtrl reference server"
    )
    add_arguments(parser)
    return run(parser.parse_args(argv), parser.prog)
