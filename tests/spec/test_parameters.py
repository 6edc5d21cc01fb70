"""pltf.spec.parameters: the table (guide 5.9, 6.4), value text, wire bounds, the store, the schema."""

from __future__ import annotations

import copy
import math
import re
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from pltf.spec.parameters import (
    TABLE_PATH,
    Category,
    DataType,
    Parameter,
    ParameterError,
    ParameterStore,
    ParameterTableError,
    Value,
    build_parameters,
    load_parameters,
)

ERRATA_PATH = TABLE_PATH.parent / "errata" / "parameters.yaml"
TABLE = load_parameters()
ROWS = list(TABLE.values())
NUMERIC = [p for p in ROWS if p.type is not DataType.BOOLEAN]
WRITABLE = [p for p in ROWS if p.writable]

# guide 5.9, tab by tab (PlanningEnabled: E-PAR-001; IpoRotVel: E-PAR-002).
GUIDE_NAMES = {
    Category.SURVEILLANCE: [
        "FlashlightEnabled",
        "PIRSensorsEnabled",
        "RadarSensorsEnabled",
        "SirenEnabled",
        "SurveillanceModeEnabled",
    ],
    Category.TRACKING_DETECTION: ["ChargeStationDetectEnabled", "PersonDetectionEnabled", "TrackingEnabled"],
    Category.MAPPING: ["MinLineLenAux", "MinLineLenMap"],
    Category.MOTION_CTRL: ["PathFollowParam1", "PathFollowParam2", "PositionStabilizationEnabled"],
    Category.PLANNING: ["PlanningEnabled", "SimuOnlineEnabledPostDis", "ViewPlanObstEnabled"],
    Category.COLLISION: ["CollCheckEnabled", "CollLaserMinDist"],
    Category.GEOM: ["DistPltfCenterToWheelAxis", "DistWheels", "PltfLength", "RadiusWheel"],
    Category.IPO: ["EndTurnEnabled", "IpoRotVel", "IpoTransVel", "StartTurnEnabled"],
    Category.LOCALIZATION: ["GlobalLocalization", "LineExtractMaxCov", "LocalLocalization", "MappingMode"],
}
ADDED_NAMES = [
    "VelWatchdogTime",
    "JoySoftVelTimeout",
    "MaxTransVel",
    "MaxRotVel",
    "MaxTransAcc",
    "MaxRotAcc",
    "TargetReachedTolPos",
    "TargetReachedTolAngle",
    "PathObstacleWaitTime",
]


def ids(rows: list[Parameter]) -> list[str]:
    return [p.name for p in rows]


def raw_table() -> dict[str, Any]:
    data = yaml.safe_load(TABLE_PATH.read_text(encoding="utf-8"))
    assert isinstance(data, dict)
    return data


def write_table(tmp_path: Path, data: dict[str, Any]) -> Path:
    path = tmp_path / "parameters.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def outside(p: Parameter) -> list[str]:
    """Texts just outside the range: min-1/max+1, and for DOUBLE also the next representable float."""
    lo, hi = p.minimum, p.maximum
    if p.type is DataType.INTEGER:
        return [str(lo - 1), str(hi + 1)]
    return [repr(lo - 1.0), repr(hi + 1.0), repr(math.nextafter(lo, -math.inf)), repr(math.nextafter(hi, math.inf))]


# --- enums and table --------------------------------------------------------------------------------
def test_enums_match_guide_6_4() -> None:
    assert [(c.name, c.value) for c in Category] == [
        ("GEOM", 0),
        ("PLANNING", 1),
        ("IPO", 2),
        ("LOCALIZATION", 3),
        ("TRACKING_DETECTION", 4),
        ("COLLISION", 5),
        ("SURVEILLANCE", 6),
        ("MOTION_CTRL", 7),
        ("MAPPING", 8),
        ("USONIC", 9),
        ("INFRARED", 10),
    ]
    assert [(t.name, t.value) for t in DataType] == [("BOOLEAN", 0), ("INTEGER", 1), ("DOUBLE", 2)]


@pytest.mark.parametrize("category", list(GUIDE_NAMES), ids=lambda c: c.name)
def test_guide_names_present(category: Category) -> None:
    for name in GUIDE_NAMES[category]:
        row = TABLE[name]
        assert row.category is category
        assert row.writable
        assert row.source.startswith("guide 5.9 ")


def test_ultrasonic_and_infrared_and_added_names() -> None:
    sensors = [f"USSensor{n:02d}{q}" for n in range(1, 17) for q in ("PosX", "PosY", "PosZ", "Angle")]
    assert [p.name for p in ROWS if p.category is Category.USONIC] == sensors
    assert all(TABLE[name].type is DataType.INTEGER for name in sensors)
    assert TABLE["InfraRedEnabled"].category is Category.INFRARED
    for name in ADDED_NAMES:
        assert not TABLE[name].writable
        assert TABLE[name].source.startswith("errata E-PAR-")
    assert len(TABLE) == sum(map(len, GUIDE_NAMES.values())) + len(sensors) + 1 + len(ADDED_NAMES)


def test_guide_misspellings_absent() -> None:
    assert "Planning Enabled" not in TABLE
    assert "IpoRotvel" not in TABLE


def test_guide_defaults() -> None:
    assert TABLE["IpoRotVel"].default == 0.6
    assert TABLE["IpoRotVel"].unit == "rad/s"
    assert TABLE["IpoTransVel"].default == 1000
    assert TABLE["IpoTransVel"].unit == "mm/s"
    assert TABLE["EndTurnEnabled"].default is True


def test_load_is_cached_but_returns_a_fresh_dict() -> None:
    first = load_parameters()
    first.clear()
    assert list(load_parameters()) == list(TABLE)
    assert load_parameters()["DistWheels"] is TABLE["DistWheels"]


def test_table_order_is_file_order() -> None:
    assert list(TABLE) == [entry["name"] for entry in raw_table()["parameters"]]


def test_python_types_follow_data_type() -> None:
    kinds = {DataType.BOOLEAN: bool, DataType.INTEGER: int, DataType.DOUBLE: float}
    for p in ROWS:
        assert type(p.default) is kinds[p.type], p.name
        if p.type is DataType.DOUBLE:
            assert type(p.minimum) is float and type(p.maximum) is float
        else:
            assert type(p.minimum) is int and type(p.maximum) is int


def test_errata_references_exist() -> None:
    errata = yaml.safe_load(ERRATA_PATH.read_text(encoding="utf-8"))
    known = {entry["id"] for entry in errata}
    assert len(known) == len(errata)
    for p in ROWS:
        referenced = set(p.errata) | set(re.findall(r"E-PAR-\d{3}", p.source))
        assert referenced <= known, p.name
        if p.source.startswith("errata "):
            assert p.source.removeprefix("errata ") in p.errata


def test_errata_format() -> None:
    errata = yaml.safe_load(ERRATA_PATH.read_text(encoding="utf-8"))
    keys = {"id", "section", "guide", "problem", "decision", "reason", "alternatives", "level"}
    for number, entry in enumerate(errata, start=1):
        assert set(entry) == keys, entry["id"]
        assert entry["id"] == f"E-PAR-{number:03d}"
        assert entry["level"] in {"MUST", "SHOULD", "MAY"}
        assert entry["alternatives"]
        for alternative in entry["alternatives"]:
            assert set(alternative) == {"reading", "original_profile"}
            assert alternative["original_profile"] in {"accept", "reject"}


# --- value text -------------------------------------------------------------------------------------
@pytest.mark.parametrize("p", ROWS, ids=ids(ROWS))
def test_default_parses_formats_and_round_trips(p: Parameter) -> None:
    text = p.format(p.default)
    assert p.parse(text) == p.default
    assert type(p.parse(text)) is type(p.default)
    assert p.format(p.parse(text)) == text


@pytest.mark.parametrize("p", NUMERIC, ids=ids(NUMERIC))
def test_range_refused_just_outside(p: Parameter) -> None:
    assert p.parse(p.format(p.minimum)) == p.minimum
    assert p.parse(p.format(p.maximum)) == p.maximum
    for text in outside(p):
        with pytest.raises(ParameterError, match="out of range"):
            p.parse(text)


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("true", True),
        ("false", False),
        ("TRUE", True),
        ("False", False),
        ("1", True),
        ("0", False),
        (" true\r\n", True),
    ],
)
def test_boolean_text(text: str, value: bool) -> None:
    assert TABLE["CollCheckEnabled"].parse(text) is value


def test_canonical_text() -> None:
    assert TABLE["CollCheckEnabled"].format(True) == "true"
    assert TABLE["CollCheckEnabled"].format(False) == "false"
    assert TABLE["IpoTransVel"].format(1000) == "1000"
    assert TABLE["USSensor13Angle"].format(-90) == "-90"
    assert TABLE["IpoRotVel"].format(0.6) == "0.6"
    assert TABLE["DistWheels"].format(430) == "430.0"  # an int is accepted for DOUBLE
    assert TABLE["IpoRotVel"].parse("0.60") == 0.6  # figure 9's display form (E-PAR-006)
    assert TABLE["IpoRotVel"].parse("6e-1") == 0.6
    assert TABLE["IpoRotVel"].parse("1") == 1.0
    assert TABLE["IpoTransVel"].parse("+1000") == 1000


BAD_TEXT = {
    "CollCheckEnabled": ["", "yes", "on", "off", "2", "-1", "t", "truex", "1.0", "tru e"],
    "IpoTransVel": ["", "1000.0", "1e3", "0x3e8", "1_000", "１０００", "10 00", "abc", "--5", "+", "1000mm/s"],
    "IpoRotVel": [
        "",
        "0,6",
        "nan",
        "NaN",
        "inf",
        "-inf",
        "1e999",
        ".",
        "e1",
        "0.6.1",
        "0x1p-1",
        "0.6rad",
        "1_0.0",
        "٠.٦",
    ],
}


@pytest.mark.parametrize(("name", "text"), [(n, t) for n, texts in BAD_TEXT.items() for t in texts])
def test_bad_text_refused_old_value_kept(name: str, text: str) -> None:
    store = ParameterStore()
    new = TABLE[name].format(TABLE[name].maximum if name != "CollCheckEnabled" else False)
    store.set_text(name, new)
    with pytest.raises(ParameterError, match=f"{name}: invalid"):
        store.set_text(name, text)
    assert store.get_text(name) == new


def test_huge_integer_text_refused() -> None:
    with pytest.raises(ParameterError):
        TABLE["IpoTransVel"].parse("9" * 5000)
    with pytest.raises(ParameterError, match="out of range"):
        TABLE["IpoTransVel"].parse("9" * 30)


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("CollCheckEnabled", 1),
        ("IpoTransVel", True),
        ("IpoTransVel", 1000.0),
        ("IpoRotVel", math.nan),
        ("IpoRotVel", "0.6"),
        ("IpoRotVel", 10**400),
        ("IpoRotVel", False),
    ],
)
def test_format_refuses_wrong_python_type(name: str, value: Any) -> None:
    with pytest.raises(ParameterError):
        TABLE[name].format(value)


def test_format_refuses_out_of_range() -> None:
    with pytest.raises(ParameterError, match="out of range"):
        TABLE["IpoTransVel"].format(TABLE["IpoTransVel"].maximum + 1)


@st.composite
def row_and_value(draw: st.DrawFn) -> tuple[Parameter, Value]:
    p = draw(st.sampled_from(ROWS))
    value: Value
    if p.type is DataType.BOOLEAN:
        value = draw(st.booleans())
    elif p.type is DataType.INTEGER:
        value = draw(st.integers(int(p.minimum), int(p.maximum)))
    else:
        value = draw(st.floats(p.minimum, p.maximum, allow_nan=False, allow_infinity=False))
    return p, value


@given(row_and_value())
def test_round_trip_any_in_range_value(case: tuple[Parameter, Value]) -> None:
    p, value = case
    text = p.format(value)
    parsed = p.parse(text)
    assert parsed == value
    assert type(parsed) is type(p.default)
    assert p.format(parsed) == text


@given(st.sampled_from(ROWS), st.text(max_size=30))
def test_any_text_parses_or_raises_parameter_error(p: Parameter, text: str) -> None:
    try:
        value = p.parse(text)
    except ParameterError:
        return
    assert p.minimum <= value <= p.maximum


# --- wire bounds (E-PAR-004) ------------------------------------------------------------------------
def test_wire_bounds() -> None:
    assert TABLE["CollCheckEnabled"].wire_bounds() == (0, 1)
    assert TABLE["IpoTransVel"].wire_bounds() == (50, 1500)
    assert TABLE["IpoRotVel"].wire_bounds() == (0, 2)  # 0.05 .. 1.5 rad/s enclosed
    for p in ROWS:
        lo, hi = p.wire_bounds()
        assert type(lo) is int and type(hi) is int
        assert -(2**31) <= lo <= p.minimum <= p.maximum <= hi < 2**31
        assert hi - p.maximum < 1 and p.minimum - lo < 1


# --- store ------------------------------------------------------------------------------------------
def test_store_defaults_items_and_text() -> None:
    store = ParameterStore()
    assert len(store) == len(TABLE)
    assert [(p.name, v) for p, v in store.items()] == [(p.name, p.default) for p in ROWS]
    assert store.get("IpoRotVel") == 0.6
    assert store.get_text("EndTurnEnabled") == "true"
    assert "IpoRotVel" in store
    assert "iporotvel" not in store


@pytest.mark.parametrize("p", WRITABLE, ids=ids(WRITABLE))
def test_store_set_and_reset(p: Parameter) -> None:
    store = ParameterStore()
    new: Value = (not p.default) if p.type is DataType.BOOLEAN else p.maximum
    if new == p.default:
        new = p.minimum
    assert store.set_text(p.name, p.format(new)) == new
    assert store.get(p.name) == new
    assert store.get_text(p.name) == p.format(new)
    store.reset()
    assert store.get(p.name) == p.default


@pytest.mark.parametrize(
    "name", ["NoSuchParameter", "iporotvel", "IPOROTVEL", "IpoRotvel", "Planning Enabled", " IpoRotVel", ""]
)
def test_store_unknown_name(name: str) -> None:
    store = ParameterStore()
    for call in (lambda: store.get(name), lambda: store.get_text(name), lambda: store.set_text(name, "1")):
        with pytest.raises(ParameterError, match="unknown parameter"):
            call()


@pytest.mark.parametrize("name", ADDED_NAMES)
def test_store_read_only(name: str) -> None:
    store = ParameterStore()
    before = store.get(name)
    with pytest.raises(ParameterError, match="read-only"):
        store.set_text(name, store.get_text(name))
    assert store.get(name) == before


def test_store_out_of_range_keeps_old_value() -> None:
    store = ParameterStore()
    store.set_text("IpoTransVel", "700")
    with pytest.raises(ParameterError, match="out of range"):
        store.set_text("IpoTransVel", "1501")
    assert store.get("IpoTransVel") == 700


def test_store_startup_values() -> None:
    store = ParameterStore(startup={"VelWatchdogTime": "200", "IpoTransVel": "800"})
    assert store.get("VelWatchdogTime") == 200
    store.set_text("IpoTransVel", "900")
    store.reset()
    assert store.get("IpoTransVel") == 800
    with pytest.raises(ParameterError, match="unknown parameter"):
        ParameterStore(startup={"Bogus": "1"})
    with pytest.raises(ParameterError, match="out of range"):
        ParameterStore(startup={"VelWatchdogTime": "0"})


def test_store_with_own_table() -> None:
    row = Parameter("X", Category.IPO, DataType.INTEGER, 1, None, 0, 9, "x", "errata E-PAR-024", True)
    store = ParameterStore({"X": row})
    assert [p.name for p, _ in store.items()] == ["X"]


# --- schema and table checks ------------------------------------------------------------------------
def test_copy_of_table_loads(tmp_path: Path) -> None:
    assert list(load_parameters(write_table(tmp_path, raw_table()))) == list(TABLE)


def _set(entry: str, key: str, value: Any) -> Any:
    def change(data: dict[str, Any]) -> None:
        row = next(e for e in data["parameters"] if e["name"] == entry)
        if value is KeyError:
            del row[key]
        else:
            row[key] = value

    return change


BROKEN = {
    "default above max": (_set("IpoTransVel", "default", 1501), "out of range"),
    "default below min": (_set("IpoRotVel", "default", 0.0), "out of range"),
    "unknown category": (_set("IpoRotVel", "category", "KINEMATICS"), "category"),
    "unknown type": (_set("IpoRotVel", "type", "FLOAT"), "type"),
    "boolean default not bool": (_set("EndTurnEnabled", "default", 1), "default"),
    "integer default fractional": (_set("IpoTransVel", "default", 1000.5), "default"),
    "boolean max 2": (_set("EndTurnEnabled", "max", 2), "max"),
    "min above max": (_set("DistWheels", "min", 5000.0), "min"),
    "blank in name": (_set("PlanningEnabled", "name", "Planning Enabled"), "name"),
    "missing unit": (_set("PltfLength", "unit", KeyError), "unit"),
    "extra key": (_set("PltfLength", "colour", "red"), "colour"),
    "bad source": (_set("PltfLength", "source", "guide 5.9 Chassis"), "source"),
    "tab and category disagree": (_set("PltfLength", "category", "IPO"), "does not match"),
    "nan bound": (_set("IpoRotVel", "max", math.nan), "finite"),
    "bound beyond INT": (_set("IpoRotVel", "max", 3e9), "max"),
    "duplicate name": (lambda d: d["parameters"].append(copy.deepcopy(d["parameters"][0])), "twice"),
    "no parameters key": (lambda d: d.clear(), "parameters"),
}


@pytest.mark.parametrize("case", list(BROKEN))
def test_broken_table_refused(tmp_path: Path, case: str) -> None:
    change, message = BROKEN[case]
    data = raw_table()
    change(data)
    with pytest.raises(ParameterTableError, match=message):
        load_parameters(write_table(tmp_path, data))
    with pytest.raises(ParameterTableError, match=message):
        build_parameters(data)


def test_not_yaml_refused(tmp_path: Path) -> None:
    path = tmp_path / "parameters.yaml"
    path.write_text("parameters: [\n", encoding="utf-8")
    with pytest.raises(ParameterTableError, match="not YAML"):
        load_parameters(path)


def test_direct_construction_checked() -> None:
    with pytest.raises(ParameterTableError, match="out of range"):
        Parameter("X", Category.IPO, DataType.INTEGER, 10, None, 0, 9, "x", "errata E-PAR-024", True)
    with pytest.raises(ParameterTableError, match="does not match"):
        Parameter("X", Category.IPO, DataType.BOOLEAN, True, None, 0, 1, "x", "guide 5.9 Geometry", True)
