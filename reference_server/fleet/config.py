"""The fleet file of ``pltf serve --fleet FILE`` and the ``--fleet N`` shortcut, as plain data.

Rules:
- A fleet file is YAML with one key ``platforms``: a list of platforms, each with ``name`` (letters, digits,
  ``-`` and ``_``; unique), ``ports`` (one or two, as ``--ports``; 0: any free port), and optionally ``pose``
  (``{x: mm, y: mm, angle: degrees}``: where the body starts, truth and estimate; without it the platform
  starts at its data dir's StartupPosition.dat), ``seed`` (default: the fleet's seed plus the platform's
  index), ``data_dir`` (default: the fleet's data dir / name) and ``node`` (with ``--ray``: the index of the
  Ray node whose shard serves it, 0 the head; with ``--processes K``: the index of its process, 0 to K-1; without
  it the nodes or processes take the platforms round-robin; in one process it is ignored). Unknown keys are
  refused: a misspelt key would otherwise be silently ignored.
- ``--fleet N``: N platforms named ``p01``..; ports ``A+4k, B+4k`` from ``--ports A,B`` (0 stays 0; E-FLEET-003); the
  poses are chosen at free places of the map at start (reference_server/fleet/places.py).
- Every error is a ``FleetError`` with a one-line message naming the file and the platform.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

PORT_STRIDE = 4  # --fleet N: platform k listens on A + 4k and B + 4k (the example: 10000, 10002, 10004, ...)
_NAME = re.compile(r"[A-Za-z0-9_-]{1,64}")
_KEYS = {"name", "ports", "pose", "seed", "data_dir", "node"}
_POSE_KEYS = {"x", "y", "angle"}

Pose = tuple[float, float, float]  # mm, mm, rad


class FleetError(ValueError):
    """The fleet description is unusable (one line)."""


@dataclass(frozen=True)
class PlatformSpec:
    name: str
    ports: tuple[int, ...]
    pose: Pose | None = None  # None: the data dir's start pose (a file) or a free place (--fleet N)
    seed: int | None = None
    data_dir: str | None = None
    node: int | None = None  # --ray: the node (0 the head), --processes: the process of its shard; None: round-robin


@dataclass(frozen=True)
class FleetSpec:
    platforms: tuple[PlatformSpec, ...]
    placed: bool = True  # False: --fleet N, the poses still to be chosen at free places of the map

    def __len__(self) -> int:
        return len(self.platforms)


def of_count(count: int, ports: Sequence[int]) -> FleetSpec:
    """``--fleet N``: N platforms with ports counted up from ``ports`` by PORT_STRIDE."""
    if count < 1:
        raise FleetError(f"--fleet N needs N >= 1, not {count}")
    top = max(ports) + PORT_STRIDE * (count - 1) if any(ports) else 0
    if top > 65535:
        raise FleetError(f"--fleet {count} from ports {ports} would need port {top} (> 65535)")
    specs = tuple(
        PlatformSpec(f"p{k + 1:02d}", tuple(p + PORT_STRIDE * k if p else 0 for p in ports)) for k in range(count)
    )
    return _checked(FleetSpec(specs, placed=False), "--fleet")


def load(path: str | Path) -> FleetSpec:
    """Read and check a fleet file."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise FleetError(f"fleet file {path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise FleetError(f"fleet file {path}: not UTF-8 text") from None
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        raise FleetError(f"fleet file {path}: not YAML{where}: {getattr(exc, 'problem', exc)}") from None
    return parse(doc, str(path))


def parse(doc: Any, where: str = "fleet") -> FleetSpec:
    if not isinstance(doc, dict) or set(doc) != {"platforms"}:
        raise FleetError(f"{where}: expected a mapping with the one key 'platforms'")
    items = doc["platforms"]
    if not isinstance(items, list) or not items:
        raise FleetError(f"{where}: 'platforms' must be a non-empty list")
    specs = tuple(_platform(item, f"{where}: platform {k + 1}") for k, item in enumerate(items))
    return _checked(FleetSpec(specs), where)


def _platform(item: Any, where: str) -> PlatformSpec:
    if not isinstance(item, dict):
        raise FleetError(f"{where}: expected a mapping (name, ports, pose, ...)")
    unknown = set(item) - _KEYS
    if unknown:
        raise FleetError(f"{where}: unknown key {sorted(unknown)[0]!r} (known: {', '.join(sorted(_KEYS))})")
    name = item.get("name")
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise FleetError(f"{where}: 'name' must be 1-64 letters, digits, '-' or '_', not {name!r}")
    where = f"{where} ({name})"
    seed = item.get("seed")
    if seed is not None and (not isinstance(seed, int) or isinstance(seed, bool)):
        raise FleetError(f"{where}: 'seed' must be an integer, not {seed!r}")
    data_dir = item.get("data_dir")
    if data_dir is not None and not isinstance(data_dir, str):
        raise FleetError(f"{where}: 'data_dir' must be a path, not {data_dir!r}")
    node = item.get("node")
    if node is not None and (not isinstance(node, int) or isinstance(node, bool) or node < 0):
        raise FleetError(f"{where}: 'node' must be a node index 0, 1, ... (0: Ray's head node), not {node!r}")
    pose = None if item.get("pose") is None else _pose(item["pose"], where)
    return PlatformSpec(name, _ports(item.get("ports"), where), pose, seed, data_dir, node)


def _ports(value: Any, where: str) -> tuple[int, ...]:
    ok = isinstance(value, list) and len(value) in (1, 2)
    ok = ok and all(isinstance(p, int) and not isinstance(p, bool) and 0 <= p <= 65535 for p in value)
    if not ok:
        raise FleetError(f"{where}: 'ports' must be a list of one or two port numbers 0..65535, not {value!r}")
    return tuple(value)


def _pose(value: Any, where: str) -> Pose:
    if not isinstance(value, dict) or set(value) != _POSE_KEYS:
        raise FleetError(f"{where}: 'pose' must be {{x: mm, y: mm, angle: degrees}}, not {value!r}")
    nums = [value[k] for k in ("x", "y", "angle")]
    if not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in nums):
        raise FleetError(f"{where}: 'pose' values must be finite numbers, not {value!r}")
    return float(nums[0]), float(nums[1]), math.radians(float(nums[2]))


def _checked(spec: FleetSpec, where: str) -> FleetSpec:
    names: set[str] = set()
    ports: dict[int, str] = {}
    for p in spec.platforms:
        if p.name in names:
            raise FleetError(f"{where}: two platforms named {p.name!r}")
        names.add(p.name)
        for port in p.ports:
            if port and port in ports:
                raise FleetError(f"{where}: port {port} of {p.name!r} is {ports[port]!r}'s too")
            if port:
                ports[port] = p.name
    return spec


__all__ = ["PORT_STRIDE", "FleetError", "FleetSpec", "PlatformSpec", "load", "of_count", "parse"]
