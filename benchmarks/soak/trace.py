"""Where does a Python process's memory grow? Run it under tracemalloc, snapshot it now and then, compare.

    python -m benchmarks.soak.trace run --out DIR --every 120 -- -m pltf.reference_server --ports 0,0 ...
    python -m benchmarks.soak.trace compare DIR [--top 15]

``run`` starts tracemalloc (``--frames`` deep), then runs the module as ``python -m`` would (runpy), and from a
daemon thread every ``--every`` s dumps a snapshot (``DIR/snap-NNN.tracemalloc``) and one JSON line to
``DIR/gc.jsonl``: seconds since the start, the traced bytes, the gc generation counts, the number of objects
the collector tracks and the 40 most common of their types (``--frames 0``: no tracemalloc, only these lines,
for a process too busy to be traced). ``compare`` sets the first snapshot against the last, grouped by
traceback, and prints the sites that grew most (size and count of their live blocks) and the gc lines' first and
last, and the object types whose counts grew most.

tracemalloc slows the process down (about 1.5-3x for allocation-heavy code): a traced soak says where memory
goes, not how fast; run it beside an untraced one, not instead of it.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import ctypes
import gc
import json
import runpy
import sys
import threading
import time
import tracemalloc
from pathlib import Path

MALLINFO2 = ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost")
IGNORED = (tracemalloc.__file__, "<frozen importlib._bootstrap>", "<frozen importlib._bootstrap_external>", "<unknown>")


class _Mallinfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in MALLINFO2]


def _mallinfo() -> dict[str, float] | None:
    """glibc's mallinfo2 in MB: ``arena`` (heap from brk), ``hblkhd`` (mmapped blocks), ``uordblks`` (in use),
    ``fordblks`` (free in the heap): in use growing is memory kept, free growing is fragmentation. None elsewhere."""
    try:
        fn = ctypes.CDLL(None).mallinfo2
    except (OSError, AttributeError):
        return None
    fn.restype = _Mallinfo2
    info = fn()
    return {k: round(getattr(info, k) / 1e6, 3) for k in ("arena", "hblkhd", "uordblks", "fordblks")}


def _rss_mb() -> float | None:
    with contextlib.suppress(OSError, StopIteration):
        line = next(x for x in Path("/proc/self/status").read_text().splitlines() if x.startswith("VmRSS:"))
        return round(int(line.split()[1]) / 1024, 3)
    return None


def _snapshots(out: Path, every: float, start: float) -> None:
    n = 0
    while True:
        time.sleep(every)
        n += 1
        if tracemalloc.is_tracing():
            snap = tracemalloc.take_snapshot().filter_traces([tracemalloc.Filter(False, f) for f in IGNORED])
            snap.dump(str(out / f"snap-{n:03d}.tracemalloc"))
        objects = gc.get_objects()
        types = collections.Counter(type(o).__qualname__ for o in objects)
        line = {
            "t": round(time.monotonic() - start, 1),
            "traced_mb": round(tracemalloc.get_traced_memory()[0] / 1e6, 3),
            "gc_counts": gc.get_count(),
            "gc_objects": len(objects),
            "types": dict(types.most_common(40)),
            "rss_mb": _rss_mb(),
            "malloc": _mallinfo(),
        }
        del objects
        with (out / "gc.jsonl").open("a", encoding="utf-8") as fh:
            fh.write(json.dumps(line) + "\n")


def run(args: argparse.Namespace) -> int:
    argv = list(args.command)
    if argv[:1] == ["--"]:
        argv = argv[1:]
    if len(argv) < 2 or argv[0] != "-m":
        print("trace: error: expected -- -m MODULE [ARGS...]", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    if args.frames > 0:  # 0: no tracemalloc (it slows every allocation), only the gc's counts by type
        tracemalloc.start(args.frames)
    start = time.monotonic()
    threading.Thread(target=_snapshots, args=(args.out, args.every, start), daemon=True, name="trace").start()
    sys.argv = [argv[1], *argv[2:]]
    try:
        runpy.run_module(argv[1], run_name="__main__", alter_sys=True)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else 0
    return 0


def compare(args: argparse.Namespace) -> int:
    snaps = sorted(args.dir.glob("snap-*.tracemalloc"))
    _types(args.dir)
    if len(snaps) < 2:
        print(f"trace: error: {args.dir} holds {len(snaps)} snapshots, compare needs two", file=sys.stderr)
        return 2
    start = snaps[args.skip if args.skip < len(snaps) - 1 else 0]
    first, last = tracemalloc.Snapshot.load(str(start)), tracemalloc.Snapshot.load(str(snaps[-1]))
    print(f"{start.name} -> {snaps[-1].name}: the {args.top} sites that grew most")
    for stat in last.compare_to(first, "traceback")[: args.top]:
        print(f"{stat.size_diff / 1e3:+10.1f} kB {stat.count_diff:+8d} blocks (now {stat.size / 1e3:.1f} kB)")
        for line in stat.traceback.format(limit=args.frames)[-2 * args.frames :]:
            print(f"      {line}")
    lines = (args.dir / "gc.jsonl").read_text(encoding="utf-8").splitlines()
    print(f"gc first: {lines[0]}\ngc last:  {lines[-1]}")
    return 0


def _types(folder: Path) -> None:
    """The object types whose counts grew most between the second gc line and the last."""
    lines = [json.loads(x) for x in (folder / "gc.jsonl").read_text(encoding="utf-8").splitlines()]
    if len(lines) < 3:
        return
    a, b = lines[1], lines[-1]
    grew = sorted(((b["types"].get(k, 0) - a["types"].get(k, 0), k) for k in b["types"]), reverse=True)[:10]
    print(f"objects {a['gc_objects']} at {a['t']} s -> {b['gc_objects']} at {b['t']} s; types that grew most:")
    print("  " + ", ".join(f"{k} {d:+d}" for d, k in grew if d > 0))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.soak.trace", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="what", required=True)
    r = sub.add_parser("run", help="run a module under tracemalloc, snapshots every --every s")
    r.add_argument("--out", type=Path, required=True)
    r.add_argument("--every", type=float, default=120.0)
    r.add_argument("--frames", type=int, default=12)
    r.add_argument("command", nargs=argparse.REMAINDER)
    c = sub.add_parser("compare", help="the sites that grew most between two snapshots")
    c.add_argument("dir", type=Path)
    c.add_argument("--top", type=int, default=15)
    c.add_argument("--frames", type=int, default=6)
    c.add_argument("--skip", type=int, default=1, help="snapshots to leave out at the start (the warm-up)")
    args = parser.parse_args(argv)
    return run(args) if args.what == "run" else compare(args)


if __name__ == "__main__":
    sys.exit(main())
