"""The fixtures of the client tests: a ``FakePlatform`` and a live reference server, each closed after its test."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import closing
from pathlib import Path

import pytest
from client_fakes import FakePlatform, LiveServer


@pytest.fixture
def fake() -> Iterator[FakePlatform]:
    with closing(FakePlatform()) as platform:
        yield platform


@pytest.fixture
def live(tmp_path: Path) -> Iterator[LiveServer]:
    with closing(LiveServer(tmp_path / "data", tmp_path / "server.log")) as server:
        yield server
