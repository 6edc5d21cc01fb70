"""pltf.spec.model: lookups over the telegram definitions."""

from __future__ import annotations

import pytest

from pltf.spec.compiler import distance_from_end
from pltf.spec.model import load_telegrams, telegram_def


def test_telegram_def_finds_every_telegram_by_name() -> None:
    for t in load_telegrams():
        assert telegram_def(t.name) == t
    with pytest.raises(KeyError):
        telegram_def("CMD_NO_SUCH_THING")


def test_the_status_timestamp_sits_at_a_fixed_distance_from_the_end() -> None:
    layout = telegram_def("CMD_GET_STATUS").layout("reply") or ()
    names = [f.name for f in layout]
    distance = distance_from_end(layout, "timestamp")
    assert distance is not None and distance >= 4
    assert distance_from_end(layout, "scan") is None  # a group: its size depends on the data
    assert distance_from_end(layout, names[-1]) == 4  # head_position, one INT
