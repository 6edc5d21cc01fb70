"""``pltf``: the toolkit's one command line.

Subcommands register themselves in ``COMMANDS`` (a table, not a chain of ifs); each module adds its own
arguments and a ``run(args) -> int``. Errors a user can cause print one line on stderr and exit 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

# name -> (module, help). The module defines add_arguments(parser) and run(args) -> int.
COMMANDS: dict[str, tuple[str, str]] = {
    "conform": ("pltf.cli.conform_cmd", "check a PlatformCtrl implementation over TCP: the conformance suite"),
    "decode": ("pltf.cli.codec_cmds", "decode frames (hex) into JSON, one object per telegram"),
    "encode": ("pltf.cli.codec_cmds", "encode a telegram from its name and fields JSON into hex"),
    "serve": ("pltf.cli.serve_cmd", "run the reference server (PlatformCtrl stand-in) on two TCP ports"),
    "fuzz": ("pltf.cli.fuzz_cmd", "fuzz an implementation (or, --in-process, the codec) for crashes and hangs"),
    "run-program": ("pltf.cli.run_program_cmd", "run a task program (guide 6.5) here, driving a platform: remote mode"),
    "gui": ("pltf.cli.gui_cmd", "PlatformCtrlGUI in the browser (guide ch. 5): map, control, monitor, parameters"),
    "stubs": ("pltf.cli.stubs_cmd", "generate the client stubs of one language (or --check a generated copy)"),
    "proxy": ("pltf.cli.proxy_cmd", "a transparent TCP proxy: decode both directions live, record the session"),
    "replay": ("pltf.cli.replay_cmd", "replay a recorded session against a target and name every reply that differs"),
    "dissector": ("pltf.cli.dissector_cmd", "write the Wireshark Lua dissector generated from spec/ (or --check it)"),
}


class _Version(argparse.Action):
    """``--version``: the installed distribution's version, looked up only when asked for."""

    def __init__(self, option_strings: Sequence[str], dest: str, help: str | None = None) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, help=help)

    def __call__(self, parser: argparse.ArgumentParser, *_: object) -> None:
        from importlib.metadata import version

        print(f"pltf {version('pltf-toolkit')}")
        parser.exit()


def make_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="pltf", description="Neobotix PlatformCtrl protocol toolkit")
    parser.add_argument("--version", action=_Version, help="print the toolkit's version and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, (module, help_text) in COMMANDS.items():
        mod = importlib.import_module(module)
        p = sub.add_parser(name, help=help_text, description=help_text)
        getattr(mod, f"add_{name.replace('-', '_')}_arguments")(p)
        p.set_defaults(_run=getattr(mod, f"run_{name.replace('-', '_')}"))
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    try:
        return int(args._run(args))
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    sys.exit(main())
