"""tests/emulator_gate.py: a test that needs the missing emulator skips with the reason, and fails under make test
(PLTF_REQUIRE_EMULATOR=1)."""

from __future__ import annotations

import pytest

from tests.emulator_gate import REQUIRE, emulator_or_skip


def test_a_missing_emulator_skips_with_the_reason(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PLTF_EMULATOR", "/no/such/emulator")
    monkeypatch.delenv(REQUIRE, raising=False)
    with pytest.raises(pytest.skip.Exception, match="PLTF_EMULATOR=/no/such/emulator is not a file"):
        emulator_or_skip()


def test_under_make_test_a_missing_emulator_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PLTF_EMULATOR", "/no/such/emulator")
    monkeypatch.setenv(REQUIRE, "1")
    with pytest.raises(pytest.fail.Exception, match=r"PLTF_REQUIRE_EMULATOR is set.*is not a file"):
        emulator_or_skip()


def test_a_built_emulator_is_handed_over(monkeypatch: pytest.MonkeyPatch, tmp_path: object) -> None:
    from pathlib import Path

    binary = Path(str(tmp_path)) / "emulator"
    binary.write_text("")
    monkeypatch.setenv("PLTF_EMULATOR", str(binary))
    monkeypatch.setenv(REQUIRE, "1")
    assert emulator_or_skip() == binary
