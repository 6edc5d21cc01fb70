"""Every command's error paths, as a table: one line on stderr, ``pltf CMD: error: ...``, the documented status.

Rows run in this process through ``pltf.cli.main.main`` (what the ``pltf`` script calls), except the ``serve``
rows that get past the parser (a port in use, a data dir that is a file), and ``gui``'s and ``proxy``'s with a
port in use: they would serve if the error were missed, so they run as a subprocess with a timeout; these
commands log to stderr, so there the error is the last line and the only error line. Two rows also run through
the installed ``pltf`` script itself.
"""

from __future__ import annotations

import json
import shlex
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from pltf.cli.main import COMMANDS, main

PLTF = Path(sys.executable).with_name("pltf")
USAGE = 2


@pytest.fixture
def dead_port() -> int:
    """A loopback port with nothing listening (bound, then closed)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture
def busy_port() -> Iterator[int]:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        yield int(s.getsockname()[1])


SESSION = [  # a pltf proxy recording (proxy/session.py): one connection, one GET_STATUS request
    {
        "format": "pltf-session",
        "version": 1,
        "started": 0.0,
        "routes": [{"listen": "127.0.0.1:1", "target": "127.0.0.1:2"}],
    },
    {"time": 0.0, "conn": 1, "port": 0, "kind": "open", "detail": ""},
    {"time": 0.01, "conn": 1, "port": 0, "kind": "frame", "direction": "request", "hex": "ff01fe020000000112"},
    {"time": 0.02, "conn": 1, "port": 0, "kind": "close", "detail": ""},
]


@pytest.fixture
def files(tmp_path: Path) -> Path:
    (tmp_path / "bad.xml").write_text("<program><task", encoding="utf-8")
    (tmp_path / "a-file").write_text("not a folder\n", encoding="utf-8")
    (tmp_path / "bad.jsonl").write_text('{"format": "pltf-session", "version": 1,\n', encoding="utf-8")
    (tmp_path / "session.jsonl").write_text("".join(json.dumps(line) + "\n" for line in SESSION), encoding="utf-8")
    return tmp_path


# (id, argv with {dead} {busy} {tmp}, status, what the message must say). Every command has rows.
ROWS = [
    ("conform/nothing-listening", "conform --target 127.0.0.1:{dead}", USAGE, "target unreachable"),
    ("conform/port-out-of-range", "conform --target 127.0.0.1:99999", USAGE, "PORT 1..65535, got '127.0.0.1:99999'"),
    ("conform/no-port", "conform --target localhost", USAGE, "expected HOST:PORT"),
    (
        "conform/second-port-out-of-range",
        "conform --target 127.0.0.1:{dead} --second-port 0",
        USAGE,
        "port number 1..65535",
    ),
    (
        "conform/unreadable-baseline",
        "conform --target 127.0.0.1:{dead} --baseline {tmp}/missing.txt",
        USAGE,
        "missing.txt",
    ),
    ("conform/no-case", "conform --target 127.0.0.1:{dead} -k no-such-case-anywhere", USAGE, "no case"),
    ("decode/bad-hex", "decode ff01zz", USAGE, "not hex"),
    ("decode/unknown-telegram", "decode ff01fe0200000001fa", USAGE, "UnknownTelegram: unknown request identifier 250"),
    ("decode/truncated", "decode ff01fe02000000050f00", USAGE, "Truncated"),
    ("decode/nothing", "decode ''", USAGE, "no telegram"),
    ("encode/bad-json", "encode CMD_SET_MODE {{mode", USAGE, "fields are not JSON"),
    ("encode/unknown-telegram", "encode CMD_NO_SUCH_THING", USAGE, "no request telegram named 'CMD_NO_SUCH_THING'"),
    ("encode/out-of-range", """encode CMD_SET_MODE '{{"mode": 99}}'""", USAGE, "99 is not a valid MotionMode"),
    ("encode/missing-field", "encode CMD_SET_MODE '{{}}'", USAGE, "missing fields ['mode']"),
    (
        "fuzz/nothing-listening",
        "fuzz --target 127.0.0.1:{dead} --duration 1 --quiet --out {tmp}/out",
        USAGE,
        "nothing listening on 127.0.0.1:{dead}",
    ),
    ("fuzz/port-out-of-range", "fuzz --target 127.0.0.1:99999 --out {tmp}/out", USAGE, "got '127.0.0.1:99999'"),
    ("fuzz/second-port-past-65535", "fuzz --target 127.0.0.1:65534 --out {tmp}/out", USAGE, "PORT+2 = 65536"),
    ("fuzz/port-0-without-launch", "fuzz --target 127.0.0.1:0 --out {tmp}/out", USAGE, "needs --launch"),
    ("fuzz/out-is-a-file", "fuzz --target 127.0.0.1:{dead} --out {tmp}/a-file", USAGE, "not a directory"),
    ("fuzz/no-target", "fuzz --out {tmp}/out", USAGE, "--target HOST:PORT is required"),
    (
        "run-program/unreadable-file",
        "run-program {tmp}/missing.xml --target 127.0.0.1:{dead}",
        USAGE,
        "No such file or directory",
    ),
    ("run-program/bad-xml", "run-program {tmp}/bad.xml --target 127.0.0.1:{dead}", USAGE, "bad.xml"),
    (
        "run-program/nothing-listening",
        "run-program " + str(Path(__file__).parents[2] / "fixtures/programs/patrol.xml") + " --target 127.0.0.1:{dead}",
        USAGE,
        "{dead}",
    ),
    ("run-program/port-out-of-range", "run-program {tmp}/bad.xml --target 127.0.0.1:65536", USAGE, "PORT 1..65535"),
    ("stubs/check-not-a-folder", "stubs --lang go --check {tmp}/missing", USAGE, "not a directory"),
    ("stubs/out-is-a-file", "stubs --lang go --out {tmp}/a-file", USAGE, "not a directory"),
    ("stubs/unknown-language", "stubs --lang cobol --out {tmp}/x", USAGE, "invalid choice: 'cobol'"),
    ("completion/unknown-shell", "completion fish", USAGE, "invalid choice: 'fish'"),
    ("gui/listen-out-of-range", "gui --target 127.0.0.1:{dead} --listen 127.0.0.1:70000", USAGE, "'127.0.0.1:70000'"),
    (
        "proxy/listen-out-of-range",
        "proxy --listen 127.0.0.1:99999 --target 127.0.0.1:{dead}",
        USAGE,
        "got '127.0.0.1:99999'",
    ),
    ("proxy/no-port", "proxy --listen 127.0.0.1:0 --target localhost", USAGE, "expected HOST:PORT"),
    ("replay/not-a-session", "replay {tmp}/bad.xml --target 127.0.0.1:{dead}", USAGE, "bad.xml:1"),
    ("dissector/out-is-a-folder", "dissector --out {tmp}", USAGE, "cannot write"),
    ("serve/port-out-of-range", "serve --ports 70000 --data-dir {tmp}/d", USAGE, "ports must be 0..65535"),
    ("serve/three-ports", "serve --ports 0,0,0 --data-dir {tmp}/d", USAGE, "one or two ports"),
    ("serve/control-port-out-of-range", "serve --control-port 65536 --data-dir {tmp}/d", USAGE, "0..65535"),
    ("gui/port-out-of-range", "gui --target 127.0.0.1:99999", USAGE, "PORT 1..65535, got '127.0.0.1:99999'"),
    ("gui/bad-listen", "gui --target 127.0.0.1:{dead} --listen nowhere", USAGE, "got 'nowhere'"),
    ("gui/bad-reply-timeout", "gui --target 127.0.0.1:{dead} --reply-timeout -1", USAGE, "number > 0"),
    ("gui/session-missing", "gui --session {tmp}/missing.jsonl", USAGE, "missing.jsonl: No such file"),
    ("gui/session-not-a-recording", "gui --session {tmp}/bad.xml", USAGE, "neither a pltf-session file"),
    ("gui/session-cut-short", "gui --session {tmp}/bad.jsonl", USAGE, "bad.jsonl:1"),
    ("gui/session-and-target", "gui --session {tmp}/session.jsonl --target 127.0.0.1:{dead}", USAGE, "not allowed"),
    (
        "proxy/port-out-of-range",
        "proxy --listen 127.0.0.1:0 --target 127.0.0.1:99999",
        USAGE,
        "PORT 1..65535, got '127.0.0.1:99999'",
    ),
    ("proxy/bad-second", "proxy --listen 127.0.0.1:0 --target 127.0.0.1:{dead} --second 70000", USAGE, "got '70000'"),
    (
        "proxy/unwritable-recording",
        "proxy --listen 127.0.0.1:0 --target 127.0.0.1:{dead} --record {tmp}/no/s.jsonl",
        USAGE,
        "cannot write the recording",
    ),
    (
        "replay/unreadable-file",
        "replay {tmp}/missing.jsonl --target 127.0.0.1:{dead}",
        USAGE,
        "No such file or directory",
    ),
    ("replay/bad-json", "replay {tmp}/bad.jsonl --target 127.0.0.1:{dead}", USAGE, "bad.jsonl:1"),
    (
        "replay/nothing-listening",
        "replay {tmp}/session.jsonl --target 127.0.0.1:{dead} --reply-timeout 2",
        USAGE,
        "{dead}",
    ),
    ("replay/port-out-of-range", "replay {tmp}/session.jsonl --target 127.0.0.1:99999", USAGE, "PORT 1..65535"),
    ("export/not-a-session", "export {tmp}/bad.xml --mcap {tmp}/s.mcap", USAGE, "bad.xml:1"),
    ("export/bad-json", "export {tmp}/bad.jsonl --mcap {tmp}/s.mcap", USAGE, "bad.jsonl:1"),
    ("export/unwritable", "export {tmp}/session.jsonl --mcap {tmp}/no/such/s.mcap", USAGE, "cannot write"),
    ("dissector/unwritable", "dissector --out {tmp}/no/such/pltf.lua", USAGE, "cannot write"),
    ("dissector/check-missing", "dissector --check {tmp}/missing.lua", USAGE, "no such file"),
]
SERVE_ROWS = [
    ("serve/port-in-use", "serve --ports {busy} --data-dir {tmp}/d --no-hardware", USAGE, "cannot listen"),
    ("serve/data-dir-is-a-file", "serve --ports 0 --data-dir {tmp}/a-file", USAGE, "data dir"),
    ("gui/listen-port-in-use", "gui --target 127.0.0.1:1 --listen 127.0.0.1:{busy}", USAGE, "cannot listen"),
    (
        "proxy/listen-port-in-use",
        "proxy --listen 127.0.0.1:{busy} --target 127.0.0.1:1 --quiet",
        USAGE,
        "cannot listen",
    ),
]


def _argv(template: str, dead: int, busy: int, tmp: Path) -> list[str]:
    return shlex.split(template.format(dead=dead, busy=busy, tmp=tmp))


def _check(command: str, status: int, want: str, got: int, err: str, log_before: bool = False) -> None:
    assert got == status, err
    assert "Traceback" not in err
    lines = err.splitlines()
    if log_before:  # the server's log lines, then the error
        assert [line for line in lines if "error:" in line] == lines[-1:], err
        lines = lines[-1:]
    assert len(lines) == 1, err
    assert lines[0].startswith(f"pltf {command}: error: "), lines[0]
    assert want in lines[0], lines[0]


@pytest.mark.parametrize(("row", "template", "status", "want"), ROWS, ids=[r[0] for r in ROWS])
def test_error_paths(
    row: str,
    template: str,
    status: int,
    want: str,
    dead_port: int,
    files: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(files)
    capsys.readouterr()
    argv = _argv(template, dead_port, 0, files)
    try:
        got = main(argv)
    except SystemExit as exc:  # argparse: the parser's own one-line error
        got = int(exc.code or 0)
    _check(row.partition("/")[0], status, want.format(dead=dead_port), got, capsys.readouterr().err)
    assert not (files / "out").exists() and not (files / "fuzz-findings").exists()  # nothing made before checks


@pytest.mark.parametrize(("row", "template", "status", "want"), SERVE_ROWS, ids=[r[0] for r in SERVE_ROWS])
def test_server_error_paths(row: str, template: str, status: int, want: str, busy_port: int, files: Path) -> None:
    done = subprocess.run(
        [str(PLTF), *_argv(template, 0, busy_port, files)],
        cwd=files,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    _check(row.partition("/")[0], status, want, done.returncode, done.stderr, log_before=True)


@pytest.mark.parametrize("argv", [["fuzz", "--target", "127.0.0.1:99999"], ["decode", "zz"]], ids=["fuzz", "decode"])
def test_the_installed_script_prints_the_same_line(argv: list[str], dead_port: int, tmp_path: Path) -> None:
    argv = [a.format(dead=dead_port) for a in argv]
    done = subprocess.run([str(PLTF), *argv], cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False)
    _check(argv[0], USAGE, "", done.returncode, done.stderr)
    assert list(tmp_path.iterdir()) == []  # ./fuzz-findings/ is not created for a refused --target


def test_a_dead_fuzz_target_is_named_by_its_port_not_the_probes(
    dead_port: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert (
        main(
            [
                "fuzz",
                "--target",
                f"127.0.0.1:{dead_port}",
                "--second-port",
                str(dead_port),
                "--duration",
                "1",
                "--quiet",
                "--out",
                str(tmp_path / "out"),
            ]
        )
        == USAGE
    )
    err = capsys.readouterr().err
    assert f"nothing listening on 127.0.0.1:{dead_port}" in err


def test_every_command_has_rows_and_refuses_an_unknown_option(capsys: pytest.CaptureFixture[str]) -> None:
    covered = {r[0].partition("/")[0] for r in ROWS + SERVE_ROWS}
    assert not set(COMMANDS) - covered, f"add error rows for: {', '.join(sorted(set(COMMANDS) - covered))}"
    for command in COMMANDS:
        with pytest.raises(SystemExit) as exc:
            main([command, "--no-such-option"])
        assert exc.value.code == USAGE
        err = capsys.readouterr().err
        assert err.splitlines() == [err.strip()] and err.startswith(f"pltf {command}: error: "), err


def test_no_command_and_an_unknown_command(capsys: pytest.CaptureFixture[str]) -> None:
    for argv, want in (([], "required: COMMAND"), (["frobnicate"], "invalid choice: 'frobnicate'")):
        with pytest.raises(SystemExit) as exc:
            main(argv)
        assert exc.value.code == USAGE
        err = capsys.readouterr().err
        assert err.startswith("pltf: error: ") and want in err and len(err.splitlines()) == 1
