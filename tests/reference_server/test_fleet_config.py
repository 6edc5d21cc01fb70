"""The fleet file and ``--fleet N`` (reference_server/fleet/config.py, places.py), and ``pltf serve --fleet``'s
usage errors: one line, exit status 2."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml

from pltf.reference_server import cli
from pltf.reference_server.fleet import config
from pltf.reference_server.fleet.places import free_places
from pltf.reference_server.world.geometry import MapGeometry
from pltf.spec.documents import DocumentKind, validate_document
from tests.reference_server.helpers import REPO

GOOD = {
    "platforms": [
        {"name": "alpha", "pose": {"x": 4000, "y": 10000, "angle": 0}, "ports": [10000, 10002]},
        {"name": "bravo", "pose": {"x": 8000, "y": 10000, "angle": 180}, "ports": [10004, 10006], "seed": 3},
    ]
}


def test_the_issue_s_example_file() -> None:
    spec = config.parse(GOOD)
    alpha, bravo = spec.platforms
    assert (alpha.name, alpha.ports, alpha.pose) == ("alpha", (10000, 10002), (4000.0, 10000.0, 0.0))
    assert bravo.pose is not None and math.isclose(bravo.pose[2], math.pi) and bravo.seed == 3


@pytest.mark.parametrize(
    ("doc", "message"),
    [
        ({"platform": []}, "the one key 'platforms'"),
        ({"platforms": []}, "non-empty list"),
        ({"platforms": [{"name": "a b", "ports": [1]}]}, "'name' must be"),
        ({"platforms": [{"name": "a", "ports": [1, 2, 3]}]}, "'ports' must be"),
        ({"platforms": [{"name": "a", "ports": [70000]}]}, "'ports' must be"),
        ({"platforms": [{"name": "a", "ports": [1], "pose": {"x": 1, "y": 2}}]}, "'pose' must be"),
        ({"platforms": [{"name": "a", "ports": [1], "pose": {"x": 1, "y": 2, "angle": "n"}}]}, "finite numbers"),
        ({"platforms": [{"name": "a", "ports": [1], "colour": "red"}]}, "unknown key 'colour'"),
        ({"platforms": [{"name": "a", "ports": [1]}, {"name": "a", "ports": [2]}]}, "two platforms named 'a'"),
        ({"platforms": [{"name": "a", "ports": [5]}, {"name": "b", "ports": [5]}]}, "port 5 of 'b' is 'a''s too"),
    ],
)
def test_a_bad_fleet_is_one_line_naming_what(doc: object, message: str) -> None:
    with pytest.raises(config.FleetError) as err:
        config.parse(doc, "f.yaml")
    assert message in str(err.value) and "\n" not in str(err.value)


def test_fleet_n_counts_the_ports_up_by_four() -> None:
    spec = config.of_count(3, [10000, 10002])
    assert [p.ports for p in spec.platforms] == [(10000, 10002), (10004, 10006), (10008, 10010)]
    assert [p.name for p in spec.platforms] == ["p01", "p02", "p03"] and not spec.placed
    assert [p.ports for p in config.of_count(2, [0, 0]).platforms] == [(0, 0), (0, 0)]
    with pytest.raises(config.FleetError, match="65535"):
        config.of_count(20000, [10000, 10002])


def test_free_places_are_stations_first_then_apart_and_off_the_walls() -> None:
    office = MapGeometry.from_tree(
        validate_document(DocumentKind.MAP, (REPO / "fixtures/maps/office.map").read_bytes())
    )
    stations = [(1000.0, 10000.0, 0.0), (1500.0, 10000.0, 0.0), (5000.0, 12200.0, math.pi / 2)]
    places = free_places(office, stations, 503.0, 100)
    assert places[:2] == [stations[0], stations[2]]  # the second station is too close to the first
    xy = [(x, y) for x, y, _ in places]
    assert min(math.dist(a, b) for i, a in enumerate(xy) for b in xy[i + 1 :]) >= 2 * 503 + 200
    with pytest.raises(config.FleetError, match="free places for"):
        free_places(office, stations, 503.0, 10000)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--fleet", "nope.yaml"], "fleet file nope.yaml"),
        (["--fleet", "2", "--motion", "ideal"], "--fleet needs --motion world"),
        (["--fleet", "2", "--control-port", "0"], "--control-port"),
        (["--shared-map"], "--shared-map needs --fleet"),
    ],
)
def test_pltf_serve_fleet_usage_errors_exit_2(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # in-process: the server's logging set-up would point the root logger at this test's captured stderr for good
    monkeypatch.setattr(cli.logging, "basicConfig", lambda **kw: None)
    assert cli.main(["--data-dir", str(tmp_path), *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err


def test_a_bad_yaml_file_is_one_line(tmp_path: Path) -> None:
    (tmp_path / "f.yaml").write_text("platforms: [\n", encoding="utf-8")
    with pytest.raises(config.FleetError, match=r"not YAML \(line"):
        config.load(tmp_path / "f.yaml")
    (tmp_path / "g.yaml").write_text(yaml.safe_dump(GOOD), encoding="utf-8")
    assert len(config.load(tmp_path / "g.yaml")) == 2
