"""``pltf proxy``: a transparent TCP proxy in front of one or both ports of a PlatformCtrl (proxy/).

It forwards bytes unchanged, shows every telegram of both directions live, and with ``--record FILE`` keeps the
session (FILE, JSON lines) and a pcapng beside it; with ``--mcap OUT`` the same as ``pltf export --mcap`` writes,
live (renamed into place when the proxy stops). The decoding, the view and the files run in a process of
their own (proxy/offload.py), so they never hold up a forwarded byte. Runs until Ctrl-C (or SIGTERM). Exit
status 0, or 2 for a user error (bad address, port in use, unwritable file).
"""

from __future__ import annotations

import argparse
import asyncio
import os
import signal
import sys
import tempfile
import time
from pathlib import Path

from pltf.cli.options import CommandError, count, exit_status, target, target_or_zero
from pltf.proxy.capture import PcapngWriter
from pltf.proxy.network import MAX_SPIN_US, SPIN_US, ProxyServer, Route
from pltf.proxy.offload import RecorderPipe
from pltf.proxy.recorder import Recorder, Sink
from pltf.proxy.session import SessionWriter
from pltf.proxy.view import Selection, View
from pltf.spec.codec import DEFAULT_MAX_LENGTH


def port_pair(text: str) -> tuple[int, int]:
    """``--second LISTEN_PORT[:TARGET_PORT]``: the second port, on the hosts of --listen and --target."""
    parts = text.split(":")
    if (
        len(parts) not in (1, 2)
        or not all(p.isascii() and p.isdigit() and int(p) < 65536 for p in parts)
        or int(parts[-1]) == 0
    ):
        raise argparse.ArgumentTypeError(
            f"expected PORT or LISTEN_PORT:TARGET_PORT (0..65535, a target port 1..65535), got {text!r}"
        )
    return int(parts[0]), int(parts[-1])


def add_proxy_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--listen",
        type=target_or_zero,
        required=True,
        metavar="HOST:PORT",
        help="where clients connect (port 0: any free port, printed at start)",
    )
    p.add_argument("--target", type=target, required=True, metavar="HOST:PORT", help="the platform (or server)")
    p.add_argument(
        "--second",
        type=port_pair,
        metavar="LPORT[:TPORT]",
        help="also proxy a second port: listen on LPORT, forward to TPORT of the target (guide 6.1: 10002)",
    )
    p.add_argument(
        "--record",
        type=Path,
        metavar="FILE",
        help="write the session to FILE (JSON lines) and the traffic to FILE with suffix .pcapng",
    )
    p.add_argument("--pcapng", type=Path, metavar="FILE", help="the pcapng file (default: beside --record)")
    p.add_argument(
        "--mcap",
        type=Path,
        metavar="OUT",
        help="also write the traffic as MCAP, as `pltf export --mcap` does (OUT appears when the proxy stops)",
    )
    p.add_argument(
        "--compression",
        choices=("lz4", "zstd", "none"),  # proxy/mcap_writer.py COMPRESSIONS (not imported: the mcap library is lazy)
        default="lz4",  # proxy/mcap_export.py DEFAULT_COMPRESSION
        help="how --mcap's chunks are compressed, as `pltf export --compression` (default: %(default)s)",
    )
    p.add_argument(
        "--filter",
        action="append",
        default=[],
        metavar="NAMES",
        help="show only these telegrams (names or globs, comma-separated, CMD_ optional; repeatable)",
    )
    p.add_argument(
        "--hide",
        action="append",
        default=[],
        metavar="NAMES",
        help="do not show these telegrams (e.g. GET_STATUS when a client polls)",
    )
    p.add_argument("--quiet", action="store_true", help="no live view (recording goes on)")
    p.add_argument("--relative-time", action="store_true", help="times in seconds since the proxy started")
    p.add_argument(
        "--max-length",
        type=count,
        default=DEFAULT_MAX_LENGTH,
        metavar="BYTES",
        help="frames longer than this are marked FrameTooLarge (default 16 MiB, erratum E-WIRE-004)",
    )
    p.add_argument(
        "--spin-us",
        type=count,
        default=SPIN_US,
        metavar="US",
        help=f"after moving bytes, keep polling for so many microseconds before sleeping (default {SPIN_US}; 0: "
        "sleep at once). Saves a thread wakeup a hop while a client and the platform talk; idle, no CPU",
    )
    p.add_argument(
        "--threads",
        action="store_true",
        help="forward with Python threads, not the C loop (the fallback when the C loop is not built)",
    )
    p.epilog = exit_status(
        ok="stopped (Ctrl-C or SIGTERM)",
        usage="usage error: bad address, --listen's port in use, the recording not writable",
    )


def _names(values: list[str]) -> list[str]:
    return [n for v in values for n in v.split(",") if n.strip()]


def _summary(recorder: Recorder) -> str:
    counts = recorder.counts
    frames = sum(counts.values()) - counts["connections"]
    text = f"proxy stopped: {counts['connections']} connections, {frames} frames"
    return text + (f", {counts['malformed']} malformed" if counts["malformed"] else "")


def _check_writable(path: Path) -> None:
    """--mcap is written beside OUT and renamed: fail here, in one line, if its folder does not take a file."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    except OSError as exc:
        raise CommandError(f"cannot write the MCAP file: {path}: {exc.strerror}") from None
    os.close(fd)
    os.unlink(tmp)


def run_proxy(args: argparse.Namespace) -> int:
    (lhost, lport), (thost, tport) = args.listen, args.target
    if args.spin_us > MAX_SPIN_US:
        raise CommandError(f"--spin-us: at most {MAX_SPIN_US} (one second), got {args.spin_us}")
    routes = [Route(lhost, lport, thost, tport)]
    if args.second is not None:
        routes.append(Route(lhost, args.second[0], thost, args.second[1]))
    started = time.time()
    pcapng_path = args.pcapng or (args.record.with_suffix(".pcapng") if args.record is not None else None)
    for path in (args.record, pcapng_path):  # fail here, in one line, not in the recorder process
        if path is not None:
            try:
                path.open("wb").close()
            except OSError as exc:
                raise CommandError(f"cannot write the recording: {path}: {exc.strerror}") from None
    if args.mcap is not None:
        _check_writable(args.mcap)

    def make() -> Recorder:  # in the recorder process
        sinks: list[Sink] = []
        flushes = []
        if not args.quiet:
            view = View(
                sys.stdout,
                Selection(_names(args.filter), _names(args.hide)),
                color=sys.stdout.isatty(),
                t0=started if args.relative_time else None,
            )
            sinks.append(view.show)
            flushes.append(view.flush)
        session = SessionWriter(args.record) if args.record is not None else None
        pcapng = PcapngWriter(pcapng_path) if pcapng_path is not None else None
        closes = []
        if args.mcap is not None:
            from pltf.proxy.mcap_export import McapFile  # the mcap library only when asked for

            mcap = McapFile(args.mcap, compression=args.compression)
            sinks.append(mcap.write)
            closes.append(mcap.close)
        return Recorder(sinks, pcapng, session, max_length=args.max_length, flushes=flushes, closes=closes)

    pipe = RecorderPipe(make, _summary)
    sys.stdout.flush()
    pipe.start()
    try:
        return asyncio.run(_serve(routes, pipe, started, args.threads, args.spin_us))
    except OSError as exc:
        pipe.close(time.time())
        raise CommandError(f"cannot listen on {lhost}: {exc.strerror or exc}") from None


async def _serve(routes: list[Route], pipe: RecorderPipe, started: float, threads: bool, spin_us: int) -> int:
    proxy = ProxyServer(routes, pipe, threads=threads, spin_us=spin_us)
    listening = await proxy.start()
    pipe.session_start(
        [(f"{h}:{p}", f"{r.target_host}:{r.target_port}") for r, (h, p) in zip(routes, listening, strict=True)], started
    )
    for route, (host, port) in zip(routes, listening, strict=True):
        print(f"proxy listening at {host}:{port} -> {route.target_host}:{route.target_port}", flush=True)
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, proxy.request_stop)
    try:
        await proxy.wait_stopped()
    finally:
        await proxy.close()
    return 0
