"""Fixtures of the conformance suite's own tests: a reference server at time scale 10, tiny fake targets."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from pltf.conformance_tests.target import Config
from pltf.harness import launch
from tests.conformance_tests.fakes import TinyTarget

TIME_SCALE = 10.0


@pytest.fixture(scope="session")
def reference() -> Iterator[launch.Launched]:
    """A reference server shared by the tests that only read or restore what they change (never CMD_EXIT)."""
    with launch.reference(time_scale=TIME_SCALE) as server:
        yield server


@pytest.fixture
def reference_config(reference: launch.Launched) -> Config:
    return Config("127.0.0.1", reference.ports[0], reference.ports[1], time_scale=TIME_SCALE, simulator=True)


@pytest.fixture
def tiny() -> Iterator[TinyTarget]:
    with TinyTarget() as target:
        yield target


@pytest.fixture
def tiny_config(tiny: TinyTarget) -> Config:
    return Config(
        "127.0.0.1", tiny.ports[0], tiny.ports[1], time_scale=10.0, reply_timeout=1.0, connect_window=1.0, min_wall=0.05
    )
