"""The example tests' reference server: one per test module, at ``TIME_SCALE``; every example is started with
``--target 127.0.0.1:PORT`` (the server's first port) and the test watches the platform through the second."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.clients.client_fakes import LiveServer
from tests.examples.runner import TIME_SCALE


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveServer]:
    root = tmp_path_factory.mktemp("server")
    live = LiveServer(root / "data", root / "server.log", TIME_SCALE)
    try:
        yield live
    finally:
        live.close()
