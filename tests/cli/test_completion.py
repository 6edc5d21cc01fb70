"""pltf.cli.completion: the bash and zsh scripts complete what the parser knows, in the real shells.

bash: the script is sourced and ``_pltf`` is called as bash calls it (COMP_LINE, COMP_POINT, COMP_WORDS split at
COMP_WORDBREAKS), the matches read from COMPREPLY. zsh: an interactive zsh in a pseudo-terminal gets the line and
a TAB (capture_completion.zsh). Skipped where the shell is not installed.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
from pathlib import Path

import pytest

from pltf.cli.completion import Completion, completion_of, describe, render_bash, render_zsh
from pltf.cli.main import COMMANDS, make_parser
from pltf.spec.model import load_telegrams

CAPTURE = Path(__file__).with_name("capture_completion.zsh")
EVERY_COMMAND = list(COMMANDS)
# (line typed, the matches expected)
CASES = [
    ("pltf ", EVERY_COMMAND),
    ("pltf de", ["decode"]),
    ("pltf --v", ["--version"]),
    ("pltf conform --target 127.0.0.1:10000 --tier ", ["smoke", "standard", "exhaustive"]),
    ("pltf conform --target 127.0.0.1:10000 --ti", ["--time-scale", "--tier"]),
    ("pltf encode CMD_SET_MO", ["CMD_SET_MODE"]),
    ("pltf run-program pat", ["patrol.xml"]),
    ("pltf run-program --target robot:10002 pat", ["patrol.xml"]),
    ("pltf fuzz --out ", ["maps"]),
    ("pltf stubs --lang ", ["python", "cpp", "java", "typescript", "go", "rust"]),
    ("pltf completion ", ["bash", "zsh"]),
    ("pltf decode --", ["--help", "--reply"]),
]


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Where the shells complete file names: a program, a text file, a folder."""
    here = tmp_path_factory.mktemp("completion")
    (here / "patrol.xml").write_text("<program/>\n")
    (here / "notes.txt").write_text("\n")
    (here / "maps").mkdir()
    return here


@pytest.fixture(scope="module")
def parser() -> argparse.ArgumentParser:
    return make_parser(load=COMMANDS)


BASH_DRIVER = r"""
source "$1"; shift
complete -p pltf >/dev/null || exit 3
for line in "$@"; do
    COMP_LINE=$line; COMP_POINT=${#line}
    IFS=$' \t\n:' read -ra COMP_WORDS <<< "$line"
    [[ $line == *[[:space:]] || $line == *: ]] && COMP_WORDS+=("")
    COMP_CWORD=$(( ${#COMP_WORDS[@]} - 1 ))
    COMPREPLY=()
    _pltf
    printf '%s\n' "${COMPREPLY[@]}" '<END>'
done
"""


def _answers(stdout: str) -> list[list[str]]:
    return [sorted({w for w in block.split() if w}) for block in stdout.split("<END>")[:-1]]


def _bash(script: Path, lines: list[str], cwd: Path) -> list[list[str]]:
    done = subprocess.run(
        ["bash", "--norc", "--noprofile", "-c", BASH_DRIVER, "bash", str(script), *lines],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    return _answers(done.stdout)


def _zsh(script: Path, lines: list[str], cwd: Path) -> list[list[str]]:
    done = subprocess.run(
        ["zsh", "-f", str(CAPTURE), str(script), *lines],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    return _answers(done.stdout)


MORE = [  # bash only: after a HOST:PORT (split at ':' by bash), and the second positional of encode
    ("pltf run-program --target robot:10002 ", ["maps", "notes.txt", "patrol.xml"]),
    ("pltf encode CMD_SET_MODE ", []),
]


@pytest.mark.skipif(shutil.which("bash") is None, reason="bash is not installed")
def test_bash(parser: argparse.ArgumentParser, folder: Path, tmp_path: Path) -> None:
    script = tmp_path / "pltf.bash"
    script.write_text(render_bash(parser))
    cases = CASES + MORE
    got = _bash(script, [line for line, _ in cases], folder)
    assert dict(zip([line for line, _ in cases], got, strict=True)) == {line: sorted(want) for line, want in cases}


@pytest.mark.skipif(shutil.which("zsh") is None, reason="zsh is not installed")
def test_zsh(parser: argparse.ArgumentParser, folder: Path, tmp_path: Path) -> None:
    script = tmp_path / "_pltf"
    script.write_text(render_zsh(parser))
    subprocess.run(["zsh", "-n", str(script)], check=True, timeout=60)
    got = _zsh(script, [line for line, _ in CASES], folder)
    assert dict(zip([line for line, _ in CASES], got, strict=True)) == {line: sorted(want) for line, want in CASES}


def test_every_option_of_every_command_is_in_both_scripts(parser: argparse.ArgumentParser) -> None:
    bash, zsh = render_bash(parser), render_zsh(parser)
    _, commands = describe(parser)
    assert [c.name for c in commands] == EVERY_COMMAND
    for command in commands:
        for option in command.options:
            for flag in option.flags:
                assert f"'{flag}[" in zsh or f"'{flag}=[" in zsh, (command.name, flag)
                assert flag in bash, (command.name, flag)


def test_what_a_value_completes_to() -> None:
    p = argparse.ArgumentParser()
    assert completion_of(p.add_argument("--tier", choices=["a", "b"])) == Completion("words", ("a", "b"))
    assert completion_of(p.add_argument("--json", metavar="FILE")) == Completion("file")
    assert completion_of(p.add_argument("program", metavar="FILE.xml")) == Completion("file")
    assert completion_of(p.add_argument("--out", metavar="DIR")) == Completion("dir")
    assert completion_of(p.add_argument("--target", metavar="HOST:PORT")) == Completion("none")
    names = describe(make_parser(load=["encode"]))[1][EVERY_COMMAND.index("encode")].positionals[0].value.words
    assert set(names) >= {t.name for t in load_telegrams()}
