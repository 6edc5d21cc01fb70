"""StatusSensors: a facade must implement every hook, or it fails at construction."""

from __future__ import annotations

from typing import Any

import pytest

from pltf.reference_server.tasks.entities import StatusSensors
from pltf.reference_server.tasks.local import LocalMachine
from pltf.reference_server.tasks.remote import RemoteMachine


def test_a_facade_without_a_hook_cannot_be_built() -> None:
    class Forgetful(StatusSensors):
        def status(self) -> Any:
            return None

    with pytest.raises(TypeError, match="debug_data"):
        Forgetful()  # type: ignore[abstract]


@pytest.mark.parametrize("facade", [LocalMachine, RemoteMachine])
def test_both_facades_implement_every_hook(facade: type[StatusSensors]) -> None:
    assert not facade.__abstractmethods__
