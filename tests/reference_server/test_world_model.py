"""The world as the server's motion model (reference_server/world/model.py): the status fields it fills stay
consistent when the map changes under a scan."""

from __future__ import annotations

from pathlib import Path

from pltf.reference_server.motion_api import Frame, advance_ideal
from pltf.reference_server.platform import Platform
from pltf.reference_server.storage import Storage
from pltf.reference_server.world.model import factory
from pltf.spec.codec import REQUESTS
from pltf.spec.documents import DocumentKind, validate_document
from pltf.spec.parameters import ParameterStore
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


def test_a_map_beyond_the_telegrams_range_is_refused_and_the_status_still_answers(tmp_path: Path) -> None:
    # E-XML-025: the fuzzer's map (a 400-digit coordinate) made every later GET_STATUS fail in the world
    storage = Storage(tmp_path / "data")
    storage.seed_from_fixtures()
    platform = Platform(storage, seed=1, motion=factory(1))
    platform.boot(0.0)
    huge = "1" + "0" * 400
    xml = f'<map><layer index="0"><line><point x="{huge}" y="0"/><point x="1" y="1"/></line></layer></map>'
    outcome = platform.handle(REQUESTS.CMD_SET_MAP(name="huge", xml=xml), 0.0)
    assert outcome.refused is not None and "2147483647" in outcome.refused
    for k in range(1, 11):
        platform.tick(k * DT)
    status = platform.handle(REQUESTS.CMD_GET_STATUS(), 10 * DT).reply
    assert status is not None and status.scan  # the office map is still active and seen


def test_walls_as_long_as_the_telegrams_allow_are_observed_without_a_huge_grid() -> None:
    # a fuzzer's map: a wall across the whole int32 range made the corner search ask for 33 TiB
    big = 2147483647
    lines = (
        f'<line><point x="-{big}" y="-{big}"/><point x="{big}" y="{big}"/></line>'
        '<line><point x="0" y="0"/><point x="0" y="-5000"/></line>'  # ends on the long wall: a T
        f'<line><point x="{big}" y="0"/><point x="-{big}" y="1"/></line>'
    )
    tree = validate_document(DocumentKind.MAP, f'<map><layer index="0">{lines}</layer></map>'.encode())
    world = factory(2)(ParameterStore().get)
    world.set_map_tree(tree)
    world.place(Frame(3000, -1000, 0.0))
    advance_ideal(world, DT, DT)
    fields = world.status_fields()
    assert fields["scan"]
