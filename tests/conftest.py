"""Hypothesis profiles: the default tier stays fast; `slow` runs the 10,000-example tier (make test-slow).

Every test leaves the root logger as it found it: a command run in-process (``pltf serve``'s ``main`` calls
``logging.basicConfig(stream=sys.stderr, force=True)``) would otherwise leave a handler on the stream pytest
captured for that test, and every later log line of the worker would end in "--- Logging error ---" on a closed
file."""

import logging
import os
from collections.abc import Iterator

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile("default", max_examples=150, deadline=None)
settings.register_profile("slow", max_examples=10_000, deadline=None, suppress_health_check=list(HealthCheck))
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))


@pytest.fixture(autouse=True)
def _root_logger_restored() -> Iterator[None]:
    root = logging.getLogger()
    before, level = set(root.handlers), root.level
    yield
    for added in [h for h in root.handlers if h not in before and type(h) is logging.StreamHandler]:
        root.removeHandler(added)  # basicConfig's (pytest's own capture handlers are its to remove)
    root.setLevel(level)
