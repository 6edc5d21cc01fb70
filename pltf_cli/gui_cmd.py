"""``pltf gui``: PlatformCtrlGUI in the browser (guide ch. 5), served by the gateway in gui/."""

from __future__ import annotations

import argparse
import asyncio
import logging
from pathlib import Path

from pltf.cli.options import exit_status, format_host_port, positive, target, target_or_zero
from pltf.gui.serve import serve


def add_gui_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--target", type=target, required=True, metavar="HOST:PORT", help="the platform (one of its two ports)"
    )
    p.add_argument(
        "--listen",
        type=target_or_zero,
        default="127.0.0.1:8080",
        metavar="HOST:PORT",
        help="where the GUI is served (default 127.0.0.1:8080; port 0: any free port)",
    )
    p.add_argument("--open", action="store_true", help="open the GUI in the default browser")
    p.add_argument(
        "--network-ini",
        type=Path,
        default=None,
        metavar="FILE",
        help="the known addresses (guide 5.2 Network.ini; default ~/.config/pltf/Network.ini)",
    )
    p.add_argument(
        "--reply-timeout",
        type=positive,
        default=None,
        metavar="S",
        help="seconds a request may wait for its reply before the platform counts as silent (default 5)",
    )
    p.epilog = exit_status(
        ok="stopped (Ctrl-C or a signal); a target that does not answer is shown, not an error",
        usage="usage error: bad options, --listen's port in use",
    )


def run_gui(args: argparse.Namespace) -> int:
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(levelname)-7s %(message)s")
    return asyncio.run(
        serve(
            format_host_port(*args.target),
            format_host_port(*args.listen),
            args.network_ini,
            args.open,
            args.reply_timeout,
        )
    )
