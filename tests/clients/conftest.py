"""The fixtures of the client tests: a ``FakePlatform`` and a live reference server, each closed after its test."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from client_fakes import FakePlatform, LiveServer


@pytest.fixture
def fake() -> Iterator[FakePlatform]:
    platform = FakePlatform()
    try:
        yield platform
    finally:
        platform.close()


@pytest.fixture
def live(tmp_path: Path) -> Iterator[LiveServer]:
    server = LiveServer(tmp_path / "data", tmp_path / "server.log")
    try:
        yield server
    finally:
        server.close()
