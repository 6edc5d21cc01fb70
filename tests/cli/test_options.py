"""pltf.cli.options: the one HOST:PORT parser, port numbers, numbers, and the exit-status epilog."""

from __future__ import annotations

import argparse
import socket

import pytest

from pltf.cli.options import (
    CommandError,
    check_listening,
    count,
    exit_status,
    format_host_port,
    parse_host_port,
    port,
    positive,
)

GOOD = [
    ("127.0.0.1:10000", 1, ("127.0.0.1", 10000)),
    ("localhost:1", 1, ("localhost", 1)),
    ("[::1]:10002", 1, ("::1", 10002)),
    ("platform.local:65535", 1, ("platform.local", 65535)),
    ("127.0.0.1:0", 0, ("127.0.0.1", 0)),
]
BAD = [
    ("127.0.0.1:99999", 1),
    ("127.0.0.1:65536", 0),
    ("127.0.0.1:0", 1),
    ("127.0.0.1", 1),
    ("127.0.0.1:", 1),
    (":10000", 1),
    ("::1:10000", 1),
    ("[]:10000", 1),
    ("host:-1", 0),
    ("host:1e3", 1),
    ("host:\u0661\u0662", 1),
    ("", 1),
]


@pytest.mark.parametrize(("text", "lowest", "want"), GOOD)
def test_host_port(text: str, lowest: int, want: tuple[str, int]) -> None:
    assert parse_host_port(text, lowest) == want


@pytest.mark.parametrize(("text", "lowest"), BAD)
def test_host_port_refused_with_the_text_in_the_message(text: str, lowest: int) -> None:
    with pytest.raises(ValueError, match="expected HOST:PORT") as info:
        parse_host_port(text, lowest)
    assert repr(text) in str(info.value)


@pytest.mark.parametrize(
    ("func", "text"),
    [
        (port, "0"),
        (port, "65536"),
        (port, "http"),
        (positive, "0"),
        (positive, "-1"),
        (positive, "inf"),
        (positive, "nan"),
        (positive, "x"),
        (count, "-1"),
        (count, "1.5"),
    ],
)
def test_numbers_refused(func: object, text: str) -> None:
    with pytest.raises(argparse.ArgumentTypeError, match=repr(text)):
        func(text)  # type: ignore[operator]


def test_numbers_accepted() -> None:
    assert (port("10002"), positive("0.5"), count("0")) == (10002, 0.5, 0)


def test_exit_status_epilog() -> None:
    text = exit_status(ok="fine", failed="findings", usage="bad input")
    assert text.splitlines() == [
        "exit status:",
        "  0    fine",
        "  1    findings",
        "  2    bad input",
        "  130  interrupted (Ctrl-C)",
    ]
    assert "  1 " not in exit_status(ok="fine", usage="bad input")


def test_check_listening() -> None:
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        number = server.getsockname()[1]
        check_listening("127.0.0.1", number, 5.0)
    with pytest.raises(CommandError, match=f"nothing listening on 127.0.0.1:{number}") as info:
        check_listening("127.0.0.1", number, 5.0)
    assert info.value.status == 2


@pytest.mark.parametrize(("host", "number"), [("127.0.0.1", 10000), ("::1", 10002), ("platform.local", 1)])
def test_format_host_port_reads_back(host: str, number: int) -> None:
    assert parse_host_port(format_host_port(host, number)) == (host, number)
