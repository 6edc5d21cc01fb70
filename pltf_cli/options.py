"""What every ``pltf`` command shares: argument types, the one error style, the exit statuses.

Rules:
- A command reports a problem it cannot go on from by raising ``CommandError(message, status)``; ``pltf.cli.main``
  prints it as one line, ``pltf CMD: error: MESSAGE``, on stderr and exits with ``status``. Never a traceback.
- Exit statuses: ``OK`` 0, ``FAILED`` 1 (findings, failed cases), ``USAGE`` 2 (usage and connection errors:
  bad arguments, an unreadable file, nothing listening), 130 on Ctrl-C. Each command states its own in its
  help (``exit_status`` builds that epilog).
- HOST:PORT is parsed by ``target`` (or ``target_or_zero``) only, ports by ``port``: one spelling of each message.
- This module imports nothing heavy: ``pltf --help`` imports it.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterable

OK, FAILED, USAGE = 0, 1, 2
INTERRUPTED = 130


class CommandError(Exception):
    """A problem the command cannot go on from: one line for the user, and the exit status."""

    def __init__(self, message: str, status: int = USAGE) -> None:
        super().__init__(message)
        self.status = status


def exit_status(ok: str, usage: str, failed: str | None = None) -> str:
    """The epilog of a command's help: what each exit status means for it."""
    lines = ["exit status:", f"  0    {ok}"]
    if failed is not None:
        lines.append(f"  1    {failed}")
    lines.append(f"  2    {usage}")
    lines.append("  130  interrupted (Ctrl-C)")
    return "\n".join(lines)


def _port_number(text: str, lowest: int) -> int | None:
    if not text.isascii() or not text.isdigit():
        return None
    value = int(text)
    return value if lowest <= value <= 65535 else None


def parse_host_port(text: str, lowest: int = 1) -> tuple[str, int]:
    """``HOST:PORT`` (an IPv6 host in brackets: ``[::1]:10000``) -> (host, port); ValueError with the reason."""
    host, sep, port = text.rpartition(":")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    elif ":" in host:
        raise ValueError(f"expected HOST:PORT (an IPv6 host in brackets: [::1]:10000), got {text!r}")
    number = _port_number(port, lowest)
    if not sep or not host or number is None:
        raise ValueError(f"expected HOST:PORT with PORT {lowest}..65535, got {text!r}")
    return host, number


def format_host_port(host: str, port_number: int) -> str:
    """(host, port) -> ``HOST:PORT``, an IPv6 host in brackets: what ``parse_host_port`` reads back."""
    return f"[{host}]:{port_number}" if ":" in host else f"{host}:{port_number}"


def target(text: str) -> tuple[str, int]:
    """argparse type of ``--target HOST:PORT`` (port 1..65535)."""
    try:
        return parse_host_port(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def target_or_zero(text: str) -> tuple[str, int]:
    """argparse type of a ``HOST:PORT`` whose port may be 0 (a port chosen when the target is launched)."""
    try:
        return parse_host_port(text, lowest=0)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def port(text: str) -> int:
    """argparse type of a TCP port number, 1..65535."""
    number = _port_number(text, 1)
    if number is None:
        raise argparse.ArgumentTypeError(f"expected a port number 1..65535, got {text!r}")
    return number


def positive(text: str) -> float:
    """argparse type of a finite number > 0 (seconds, a time scale)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def count(text: str) -> int:
    """argparse type of a whole number >= 0 (cases, examples, re-runs)."""
    if not text.isascii() or not text.isdigit():
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}")
    return int(text)


def completes(action: argparse.Action, what: str | Iterable[str] | Callable[[], Iterable[str]]) -> None:
    """Tell ``pltf completion`` what a value of ``action`` completes to: "file", "dir", words, or a function giving
    the words (called only when the script is generated)."""
    action.complete = what  # type: ignore[attr-defined]


def check_listening(host: str, port_number: int, timeout: float) -> None:
    """CommandError (status 2) unless something accepts a TCP connection on host:port (closed at once)."""
    import socket

    try:
        with socket.create_connection((host, port_number), timeout=timeout):
            pass
    except OSError as exc:
        reason = exc.strerror or str(exc) or type(exc).__name__
        raise CommandError(f"nothing listening on {host}:{port_number} ({reason})") from None
