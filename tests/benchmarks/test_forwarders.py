"""The baseline forwarders of ``proxy.get_position`` (benchmarks/forwarders/, run as bench_proxy.py runs them) over
real loopback sockets, untimed: bytes both ways unchanged however the kernel cuts them, a FIN passed on with the
other direction still open, and the next connection served after the first is done (the benchmark connects many
times through one forwarder)."""

from __future__ import annotations

import random
import socket
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from benchmarks.bench_proxy import C_FLOOR, PY_FLOOR, build_c_forwarder, forwarder_commands, listening
from tests.proxy.helpers import read_exactly, read_to_end

BULK = random.Random(21).randbytes(300_000)  # larger than a loopback segment and the forwarders' 64 KiB reads


@pytest.fixture
def target() -> Iterator[socket.socket]:
    with socket.create_server(("127.0.0.1", 0)) as server:
        server.settimeout(10)
        yield server


@pytest.fixture(params=[C_FLOOR, PY_FLOOR])
def forwarder(request: pytest.FixtureRequest, target: socket.socket, tmp_path: Path) -> Iterator[int]:
    """The forwarder's listening port, forwarding to ``target``."""
    commands = forwarder_commands(tmp_path, target.getsockname()[1])
    if request.param not in commands:
        pytest.skip(f"{request.param}: {build_c_forwarder(tmp_path)}")  # the reason: no C compiler, or cc failed
    with listening(commands[request.param], stop_signal=15) as port:
        yield port


def _connect(port: int, target: socket.socket) -> tuple[socket.socket, socket.socket]:
    client = socket.create_connection(("127.0.0.1", port), timeout=10)
    accepted, _ = target.accept()
    accepted.settimeout(10)
    return client, accepted


def test_bytes_pass_both_ways_and_a_fin_is_passed_on(forwarder: int, target: socket.socket) -> None:
    client, server = _connect(forwarder, target)
    with client, server:
        client.sendall(b"request")
        assert read_exactly(server, 7) == b"request"
        server.sendall(b"reply")
        assert read_exactly(client, 5) == b"reply"
        sender = threading.Thread(target=client.sendall, args=(BULK,))
        sender.start()
        assert read_exactly(server, len(BULK)) == BULK
        sender.join()
        client.shutdown(socket.SHUT_WR)
        assert server.recv(1) == b""  # the client's FIN reached the target
        server.sendall(BULK)  # ... and the other direction still forwards
        server.shutdown(socket.SHUT_WR)
        assert read_to_end(client) == BULK  # then the target's FIN reached the client


def test_the_next_connection_is_served(forwarder: int, target: socket.socket) -> None:
    for k in range(3):
        client, server = _connect(forwarder, target)
        with client, server:
            client.sendall(b"ping %d" % k)
            assert read_exactly(server, 6) == b"ping %d" % k
            server.sendall(b"pong %d" % k)
            assert read_exactly(client, 6) == b"pong %d" % k
            client.shutdown(socket.SHUT_WR)
            assert server.recv(1) == b""
