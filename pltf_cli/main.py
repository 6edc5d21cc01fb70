"""``pltf``: the toolkit's one command line.

Rules:
- Subcommands are the rows of ``COMMANDS`` (a table, not a chain of ifs): name -> (module, one-line help). The
  module defines ``add_<name>_arguments(parser)`` and ``run_<name>(args) -> int`` (``-`` in a name becomes ``_``).
- Only the chosen command's module is imported: ``pltf --help`` prints the table's help strings, ``pltf decode``
  loads the codec and nothing of the server (issue 18: both start in <= 0.3 s; benchmarks/bench_cli.py).
  ``pltf completion`` is the one command that loads them all, to describe every option.
- One error style (pltf.cli.options): ``pltf CMD: error: MESSAGE``, one line on stderr, never a traceback; exit
  status 2 for usage and connection errors, 1 for findings and failed cases, as each command's help states.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Collection, Sequence
from typing import NoReturn

from pltf.cli.options import INTERRUPTED, USAGE, CommandError

# name -> (module, help). The module defines add_<name>_arguments(parser) and run_<name>(args) -> int.
COMMANDS: dict[str, tuple[str, str]] = {
    "conform": ("pltf.cli.conform_cmd", "check a PlatformCtrl implementation over TCP: the conformance suite"),
    "decode": ("pltf.cli.codec_cmds", "decode frames (hex) into JSON, one object per telegram"),
    "encode": ("pltf.cli.codec_cmds", "encode a telegram from its name and fields JSON into hex"),
    "serve": ("pltf.cli.serve_cmd", "run the reference server (PlatformCtrl stand-in) on its TCP ports"),
    "fuzz": ("pltf.cli.fuzz_cmd", "fuzz an implementation (or, --in-process, the codec) for crashes and hangs"),
    "run-program": ("pltf.cli.run_program_cmd", "run a task program (guide 6.5) here, driving a platform: remote mode"),
    "gui": ("pltf.cli.gui_cmd", "PlatformCtrlGUI in the browser (guide ch. 5): map, control, monitor, parameters"),
    "stubs": ("pltf.cli.stubs_cmd", "generate the client stubs of one language (or --check a generated copy)"),
    "proxy": ("pltf.cli.proxy_cmd", "a transparent TCP proxy: decode both directions live, record the session"),
    "replay": ("pltf.cli.replay_cmd", "replay a recorded session against a target and name every reply that differs"),
    "export": ("pltf.cli.export_cmd", "write a recorded session as MCAP (Foxglove's schemas), for Foxglove and ROS 2"),
    "dissector": ("pltf.cli.dissector_cmd", "write the Wireshark Lua dissector generated from spec/ (or --check it)"),
    "completion": ("pltf.cli.completion", "print the bash or zsh completion script of pltf"),
}

EPILOG = """\
Run `pltf COMMAND --help` for a command's options and exit statuses. Every command reports a problem as one
line on stderr, `pltf COMMAND: error: ...`: exit status 2 for usage and connection errors, 1 for findings and
failed cases, 3 for an internal error (a bug in pltf: PLTF_TRACEBACK=1 shows where)."""
INTERNAL = 3


class Parser(argparse.ArgumentParser):
    """argparse with the one error style: ``PROG: error: MESSAGE`` as a single line, no usage block."""

    commands: dict[str, Parser]

    def error(self, message: str) -> NoReturn:
        self.exit(USAGE, f"{self.prog}: error: {message}\n")


class _Version(argparse.Action):
    """``--version``: the installed distribution's version, looked up only when asked for."""

    def __init__(self, option_strings: Sequence[str], dest: str, help: str | None = None) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, help=help)

    def __call__(self, parser: argparse.ArgumentParser, *_: object) -> None:
        from importlib.metadata import PackageNotFoundError, version

        try:
            number = version("pltf-toolkit")
        except PackageNotFoundError:
            number = "(not installed: run from a checkout)"
        print(f"pltf {number}")
        parser.exit()


def _hook(name: str, kind: str) -> str:
    snake = name.replace("-", "_")
    return f"add_{snake}_arguments" if kind == "add" else f"run_{snake}"


def make_parser(load: Collection[str] = ()) -> Parser:
    """The parser of every command; only the commands in ``load`` get their arguments (their module imported)."""
    formatter = argparse.RawDescriptionHelpFormatter
    parser = Parser(
        prog="pltf", description="Neobotix PlatformCtrl protocol toolkit", epilog=EPILOG, formatter_class=formatter
    )
    parser.add_argument("--version", action=_Version, help="print the toolkit's version and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    parser.commands = {}
    for name, (module, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text, formatter_class=formatter)
        if name in load:
            mod = importlib.import_module(module)
            getattr(mod, _hook(name, "add"))(p)
            p.set_defaults(_run=getattr(mod, _hook(name, "run")))
        parser.commands[name] = p
    return parser


def _chosen(argv: Sequence[str]) -> str | None:
    """The command word: the first argument that is not an option (``pltf`` itself has only flags)."""
    return next((a for a in argv if not a.startswith("-")), None)


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    chosen = _chosen(argv)
    try:
        parser = make_parser(load=[chosen] if chosen in COMMANDS else [])
    except ImportError as exc:  # a partial install, or a dependency the command needs is missing
        return _fail(f"pltf {chosen}", f"cannot load the command: {exc}", USAGE)
    args, extra = parser.parse_known_args(argv)
    prog = parser.commands[args.command].prog
    if extra:
        parser.commands[args.command].error(f"unrecognized arguments: {' '.join(extra)}")
    try:
        return int(args._run(args))
    except CommandError as exc:
        return _fail(prog, str(exc), exc.status)
    except KeyboardInterrupt:
        return INTERRUPTED
    except BrokenPipeError:  # `pltf decode ... | head`: the reader left; nothing to report, nothing to flush
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:  # a file or a connection the command did not expect to fail
        where = f"{exc.filename}: " if exc.filename else ""
        return _fail(prog, f"{where}{exc.strerror or exc}", USAGE)
    except Exception as exc:
        if os.environ.get("PLTF_TRACEBACK"):
            raise
        return _fail(
            prog, f"internal error, a bug in pltf: {type(exc).__name__}: {exc} (PLTF_TRACEBACK=1 shows where)", INTERNAL
        )


def _fail(prog: str, message: str, status: int) -> int:
    print(f"{prog}: error: {' '.join(message.split())}", file=sys.stderr)
    return status


if __name__ == "__main__":
    sys.exit(main())
