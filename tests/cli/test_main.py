"""pltf.cli.main: the COMMANDS table, lazy subcommand modules, --version, help texts and the catch-all."""

from __future__ import annotations

import argparse
import importlib
import json
import subprocess
import sys
from pathlib import Path

import pytest

from pltf.cli import codec_cmds
from pltf.cli.main import COMMANDS, EPILOG, main, make_parser

PLTF = Path(sys.executable).with_name("pltf")
SUBCOMMAND_MODULES = {module for module, _ in COMMANDS.values()}
HEAVY = {
    "rich",
    "numpy",
    "scipy",
    "pymunk",
    "can",
    "cantools",
    "lxml",
    "jsonschema",
    "yaml",
    "asyncio",
    "pltf.reference_server",
    "pltf.conformance_tests",
    "pltf.fuzz",
    "pltf.client",
    "pltf.stubgen",
}


def _modules_after(argv: list[str], stdin: str = "") -> set[str]:
    """sys.modules after ``pltf ARGV`` ran in a fresh interpreter (its output discarded)."""
    code = (
        "import contextlib, io, json, sys\nfrom pltf.cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n        main(json.loads(sys.argv[1]))\n    except SystemExit:\n        pass\n"
        "print(json.dumps(sorted(sys.modules)))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, json.dumps(argv)],
        input=stdin,
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    return set(json.loads(done.stdout.splitlines()[-1]))


def _under(modules: set[str], names: set[str]) -> set[str]:
    return {n for n in names if n in modules or any(m.startswith(n + ".") for m in modules)}


def test_help_imports_no_subcommand_module() -> None:
    modules = _modules_after(["--help"])
    assert modules & SUBCOMMAND_MODULES == set()
    assert _under(modules, HEAVY | {"pltf.spec"}) == set()


@pytest.mark.parametrize(
    "argv",
    [["decode", "ff01fe02000000050f00000003"], ["encode", "CMD_SET_MODE", '{"mode": 3}'], ["decode", "--help"]],
    ids=["decode", "encode", "decode-help"],
)
def test_decode_and_encode_import_only_the_codec(argv: list[str]) -> None:
    modules = _modules_after(argv)
    assert modules & SUBCOMMAND_MODULES == {"pltf.cli.codec_cmds"}
    assert _under(modules, HEAVY) == set()


def test_the_table_names_importable_modules_with_both_hooks() -> None:
    for name, (module, help_text) in COMMANDS.items():
        assert help_text and not help_text.endswith("."), name
        mod = importlib.import_module(module)
        snake = name.replace("-", "_")
        assert callable(getattr(mod, f"add_{snake}_arguments")) and callable(getattr(mod, f"run_{snake}")), name


def test_every_option_has_help_and_every_command_states_its_exit_statuses() -> None:
    parser = make_parser(load=COMMANDS)
    for name, sub in parser.commands.items():
        for action in sub._actions:
            where = f"pltf {name} {action.option_strings or action.dest}"
            assert action.help and action.help != argparse.SUPPRESS, where
        epilog = sub.epilog or ""
        assert epilog.startswith("exit status:") and "\n  0 " in epilog and "\n  2 " in epilog, name
        assert "exit status:" in sub.format_help()  # printed as written (RawDescriptionHelpFormatter)
    assert "exit status 2 for usage and connection errors, 1 for findings" in " ".join(EPILOG.split())


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.startswith("pltf 0.")


def test_a_bug_is_one_line_with_status_3_and_its_traceback_on_request(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def broken(args: argparse.Namespace) -> int:
        raise ZeroDivisionError("division by zero")

    monkeypatch.setattr(codec_cmds, "run_decode", broken)
    assert main(["decode", "00"]) == 3
    err = capsys.readouterr().err
    assert err.startswith("pltf decode: error: internal error") and "ZeroDivisionError" in err
    assert len(err.splitlines()) == 1
    monkeypatch.setenv("PLTF_TRACEBACK", "1")
    with pytest.raises(ZeroDivisionError):
        main(["decode", "00"])


def test_a_reader_that_leaves_early_is_no_error(tmp_path: Path) -> None:
    frames = "ff01fe02000000050f00000003\n" * 20_000  # ~1.5 MB of JSON: more than a pipe holds
    with subprocess.Popen(
        [str(PLTF), "decode", "-"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    ) as proc:
        assert proc.stdin is not None and proc.stdout is not None and proc.stderr is not None
        proc.stdin.write(frames)
        proc.stdin.close()
        proc.stdout.readline()
        proc.stdout.close()  # as `| head -1` does
        assert proc.wait(timeout=120) == 0
        assert proc.stderr.read() == ""
