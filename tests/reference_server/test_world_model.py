"""The world as the server's motion model (reference_server/world/model.py): the status fields it fills stay
consistent when the map changes under a scan."""

from __future__ import annotations

from pathlib import Path

from reference_server.motion_api import Frame, advance_ideal
from reference_server.world.model import factory
from spec.documents import DocumentKind, validate_document
from spec.parameters import ParameterStore
from tests.reference_server.helpers import REPO

DT = 0.02


def _map(circles: int) -> object:
    body = "".join(f'<circle><center x="{2000 + 600 * k}" y="1000"/><radius r="200"/></circle>' for k in range(circles))
    xml = f'<?xml version="1.0"?><map Version="1.0"><layer index="0">{body}</layer></map>'
    return validate_document(DocumentKind.MAP, xml.encode())


def test_a_new_map_after_a_scan_leaves_no_stale_observation() -> None:
    world = factory(3)(ParameterStore().get)
    world.set_map_tree(_map(4))
    world.place(Frame(1000, 1000, 0.0))
    now = 0.0
    for _ in range(10):  # 0.2 s: the laser (10 Hz) has scanned the four pillars
        now += DT
        advance_ideal(world, now, DT)
    assert world.status_fields()["circles"]  # the pillars are seen
    world.set_map_tree(_map(1))  # fewer circles: the old scan's hit ids point past the new scene
    fields = world.status_fields()
    assert fields["circles"] == ()  # nothing seen until the next scan
    for _ in range(10):
        now += DT
        advance_ideal(world, now, DT)
    assert len(world.status_fields()["circles"]) == 1


def test_the_office_map_is_seen_by_the_laser() -> None:
    world = factory(1)(ParameterStore().get)
    tree = validate_document(DocumentKind.MAP, Path(REPO / "fixtures" / "maps" / "office.map").read_bytes())
    world.set_map_tree(tree)
    world.place(Frame(2000, 2000, 0.0))
    advance_ideal(world, DT, DT)
    fields = world.status_fields()
    assert fields["scan"] and fields["localization_lost"] == 0
