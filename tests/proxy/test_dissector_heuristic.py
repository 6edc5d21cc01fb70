"""The dissector's heuristic (issue 32): a TCP stream that starts with FF 01 FE 02 and a sane length is
PlatformCtrl on ANY port, in both directions, found by tshark without Decode As (``-d``).

The capture is a real one: ``pltf proxy --record`` in front of the reference server, both on ephemeral ports,
a client asks for the position; tshark reads the proxy's pcapng with the generated dissector and nothing else.
"""

from __future__ import annotations

import re
import signal
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

from pltf.harness import launch
from pltf.proxy.dissector import OUTPUT, PORTS, field_abbr
from pltf.spec.codec import REQUESTS, TelegramDecoder, encode
from tests.proxy.test_dissector import write_capture
from tests.proxy.tshark import Shown, run_tshark, shown_value, telegrams
from tests.proxy.vectors import REPLIES

ROOT = Path(__file__).resolve().parents[2]
POSITION = ("x", "y", "angle", "vel_trans", "vel_rot")
KINDS = {"x": "INT", "y": "INT", "angle": "DOUBLE", "vel_trans": "DOUBLE", "vel_rot": "DOUBLE"}


def _get_position(port: int) -> dict[str, Any]:
    """One CMD_GET_POSITION on a connection of its own; the reply's fields."""
    decoder = TelegramDecoder("reply")
    with socket.create_connection(("127.0.0.1", port), timeout=20) as sock:
        sock.sendall(encode(REQUESTS.CMD_GET_POSITION()))
        while True:
            chunk = sock.recv(65536)
            assert chunk, "the server closed without a reply"
            decoder.receive_data(chunk)
            replies = list(decoder)
            if replies:
                return {name: getattr(replies[0], name) for name in POSITION}


def _record(tmp_path: Path) -> tuple[Path, dict[str, Any], int]:
    """A capture by ``pltf proxy --record`` of a GET_POSITION exchange with the reference server; the reply's
    fields and the server's port."""
    session = tmp_path / "s.jsonl"
    with launch.reference(time_scale=10) as server:
        port = server.ports[0]
        cmd = [sys.executable, "-m", "pltf.cli.main", "proxy", "--listen", "127.0.0.1:0", "--quiet"]
        cmd += ["--target", f"127.0.0.1:{port}", "--record", str(session)]
        with subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) as proc:
            try:
                assert proc.stdout is not None
                found = re.search(r"listening at [\d.]+:(\d+)", proc.stdout.readline())
                assert found is not None
                fields = _get_position(int(found.group(1)))
                proc.send_signal(signal.SIGINT)
                _, err = proc.communicate(timeout=30)
            finally:
                proc.kill()
    assert proc.returncode == 0, err
    return session.with_suffix(".pcapng"), fields, port


def _values(shown: Shown, direction: str) -> dict[str, Any]:
    out = {}
    for name in POSITION:
        abbr = field_abbr(direction, "CMD_GET_POSITION", name)  # type: ignore[arg-type]
        (show, showname) = next((s, sn) for n, s, sn in shown.fields if n == abbr)
        out[name] = shown_value(KINDS[name], show, showname)
    return out


def test_tshark_finds_get_position_on_an_ephemeral_port_without_decode_as(tmp_path: Path) -> None:
    pcapng, fields, port = _record(tmp_path)
    assert port not in PORTS
    shown = telegrams(run_tshark(pcapng))  # no -d
    labels = [s.label.split(" (")[0] for s in shown]
    assert labels == ["PlatformCtrl request: CMD_GET_POSITION", "PlatformCtrl reply: CMD_GET_POSITION"], labels
    assert _values(shown[1], "reply") == fields
    assert all(not s.experts for s in shown)


def test_both_directions_on_two_unregistered_ports_whichever_is_lower(tmp_path: Path) -> None:
    """The side that sends the first frame is the client (guide 6.1: the platform only answers), whether its
    port is above or below the server's."""
    request = encode(REQUESTS.CMD_GET_POSITION())
    reply = bytes.fromhex(next(v["hex"] for v in REPLIES if v["telegram"] == "CMD_GET_POSITION"))
    exchange = [(True, request), (False, reply), (True, request), (False, reply)]
    path = tmp_path / "two.pcapng"
    write_capture(path, [(51000, 40404, exchange), (33333, 45000, exchange)])
    labels = [s.label.split(" (")[0] for s in telegrams(run_tshark(path))]
    assert labels == ["PlatformCtrl request: CMD_GET_POSITION", "PlatformCtrl reply: CMD_GET_POSITION"] * 4, labels


def test_other_streams_are_not_taken_for_platformctrl(tmp_path: Path) -> None:
    """Not the header, a length of zero (no identifier) or over the maximum (erratum E-WIRE-004), too short to
    tell: plain TCP, not a malformed PlatformCtrl frame."""
    streams = [
        b"GET / HTTP/1.1\r\nHost: x\r\n\r\n",
        bytes.fromhex("ff01fe0300000001") + b"\x4a",
        bytes.fromhex("ff01fe0200000000"),
        bytes.fromhex("ff01fe0201000001") + b"\x4a" * 16,
        bytes.fromhex("ff01fe"),
    ]
    path = tmp_path / "other.pcapng"
    write_capture(path, [(52000 + k, 41000 + k, [(True, s)]) for k, s in enumerate(streams)])
    assert telegrams(run_tshark(path)) == []


def test_the_generated_dissector_registers_the_heuristic() -> None:
    assert 'pltf:register_heuristic("tcp", heuristic)' in OUTPUT.read_text()
