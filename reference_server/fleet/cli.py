"""``pltf serve --fleet FILE|N``: build the fleet from the command line's options and serve it until it exits.

Rules: the options are those of ``pltf serve`` (reference_server/cli.py); ``--fleet`` is a fleet file
(reference_server/fleet/config.py) or a count. Each platform's data dir is the file's ``data_dir`` or
``--data-dir``/NAME, seeded from the repository's fixtures when empty; its seed the file's or ``--seed`` plus its
index. ``--ray ADDRESS``: the fleet as shards on a Ray cluster (reference_server/fleet/ray_shards.py);
``--processes K``: as shards in K local processes (reference_server/fleet/local_shards.py). What a
single platform has and a fleet cannot share (one CAN channel, one fault-control port, the ideal
wheels that have no body) is refused with one line. User errors exit 2, as ``pltf serve``'s.
"""

from __future__ import annotations

import argparse
import gc
import logging
import sys
from collections.abc import Callable
from pathlib import Path

from pltf.reference_server import hardware_link
from pltf.reference_server.fleet import network
from pltf.reference_server.fleet.config import FleetError, FleetSpec, load, of_count
from pltf.reference_server.fleet.fleet import Fleet, FleetPlatform
from pltf.reference_server.platform import Platform
from pltf.reference_server.storage import Storage
from pltf.reference_server.tasks.local import factory as program_factory
from pltf.reference_server.world.model import factory as world_factory

log = logging.getLogger("pltf.server")

# what a fleet refuses: (option is set, the one-line reason)
_REFUSED: tuple[tuple[Callable[[argparse.Namespace], bool], str], ...] = (
    (lambda a: a.motion != "world", "--fleet needs --motion world: the platforms are bodies in one world"),
    (lambda a: a.control_port is not None, "--control-port serves one platform; it is not available with --fleet"),
    (lambda a: a.can_channel is not None, "--can-channel would put every platform's boards on one bus"),
    (lambda a: _ray(a) and _processes(a) > 0, "--ray and --processes: choose one (Ray places the shards itself)"),
    (lambda a: _processes(a) < 0, "--processes must be at least 1"),
    (lambda a: _split(a) and a.shared_map, "--shared-map hands a map on in one process: not with --ray, --processes"),
    (lambda a: _split(a) and getattr(a, "ray_lag", 1) < 1, "--ray-lag must be at least 1 (period)"),
)


def _ray(args: argparse.Namespace) -> bool:
    return getattr(args, "ray", None) is not None


def _processes(args: argparse.Namespace) -> int:
    """``--processes K`` as given: 0 when not given; -1 when below 1 (refused)."""
    k = getattr(args, "processes", None)
    return 0 if k is None else (k if k >= 1 else -1)


def _split(args: argparse.Namespace) -> bool:
    """The fleet is served by shards of their own (on Ray, or in local processes): more than one process."""
    return _ray(args) or _processes(args) > 1


def spec_of(args: argparse.Namespace) -> FleetSpec:
    """The fleet of ``--fleet``: a count or a file."""
    text = str(args.fleet)
    if text.isdigit():
        return of_count(int(text), args.ports)
    return load(text)


def build_platforms(spec: FleetSpec, args: argparse.Namespace) -> list[Platform]:
    platforms: list[Platform] = []
    for k, p in enumerate(spec.platforms):
        root = Path(p.data_dir) if p.data_dir is not None else Path(args.data_dir) / p.name
        storage = Storage(root)
        storage.seed_from_fixtures()
        seed = p.seed if p.seed is not None else args.seed + k
        link = None if args.no_hardware else hardware_link.factory(args.can_interface, None)
        platforms.append(
            FleetPlatform(storage, seed=seed, motion=world_factory(seed), program=program_factory, hardware=link)
        )
    return platforms


def run(args: argparse.Namespace, prog: str) -> int:
    for refused, reason in _REFUSED:
        if refused(args):
            print(f"{prog}: error: {reason}", file=sys.stderr)
            return 2
    try:
        spec = spec_of(args)
    except FleetError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    if _ray(args):
        from pltf.reference_server.fleet import ray_shards  # Ray only under --ray

        return ray_shards.run(spec, args, prog)
    if _processes(args) > 1:
        from pltf.reference_server.fleet import local_shards

        return local_shards.run(spec, args, prog)
    platforms: list[Platform] = []
    try:
        platforms = build_platforms(spec, args)
        fleet = Fleet(spec, platforms, shared_map=args.shared_map)
        gc.collect()
        gc.freeze()  # as pltf serve: what lives as long as the process is not walked again and again
        return network.run(fleet, args.host, args.time_scale)
    except FleetError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"{prog}: error: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except (ValueError, ImportError) as exc:  # python-can: an unknown interface
        print(f"{prog}: error: CAN interface {args.can_interface}: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 0
    finally:
        for platform in platforms:
            platform.close()
