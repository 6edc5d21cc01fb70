"""Whether a test that needs the Go emulator (emulator/, issue 17) runs, fails or skips.

Rules:
- Outside ``make test`` a test whose emulator is missing (Go not installed, the build failed) is skipped with the
  reason (``pytest -ra`` lists it).
- ``make test`` builds the emulator first and sets ``PLTF_REQUIRE_EMULATOR=1``: there the same test fails with the
  reason, so an emulator check never passes silently by not running.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from pltf.harness.launch import emulator_binary, why_no_emulator

REQUIRE = "PLTF_REQUIRE_EMULATOR"


def required() -> bool:
    return os.environ.get(REQUIRE, "") not in ("", "0")


def missing(why: str) -> None:
    """The emulator (or its toolchain) is missing: fail under ``PLTF_REQUIRE_EMULATOR``, else skip. Never returns."""
    if required():
        pytest.fail(f"no emulator ({REQUIRE} is set, as make test sets it): {why}", pytrace=False)
    pytest.skip(f"no emulator: {why}")


def emulator_or_skip() -> Path:
    """The emulator's binary; without one the test fails (``PLTF_REQUIRE_EMULATOR``) or is skipped."""
    binary = emulator_binary()
    if binary is None:
        missing(why_no_emulator())
    assert binary is not None
    return binary
