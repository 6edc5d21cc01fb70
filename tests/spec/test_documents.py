"""spec/documents.py and spec/schemas/*.xsd: fixtures, guide ambiguities (spec/errata/xml.yaml), safety.

Every schema verdict is checked twice: through spec/documents.py (lxml/libxml2) and with the independent
`xmlschema` package against the same XSD, so the schemas are never only tested against one engine.
"""

from __future__ import annotations

import contextlib
import importlib.util
import itertools
import math
import re
import sys
from collections.abc import Iterable
from functools import cache
from pathlib import Path

import pytest
import xmlschema
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from pltf.spec.documents import (
    DEFAULT_MAX_SIZE,
    MAX_DEPTH,
    SCHEMA_DIR,
    DocumentError,
    DocumentKind,
    detect_kind,
    schema_path,
    validate_document,
)

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "fixtures"
OFFICE_MAP = FIXTURES / "maps" / "office.map"
OFFICE_RM = FIXTURES / "roadmaps" / "office.rm"
ERRATA = ROOT / "spec" / "errata" / "xml.yaml"

MAP, ROADMAP, PROGRAM, TASK = DocumentKind.MAP, DocumentKind.ROADMAP, DocumentKind.PROGRAM, DocumentKind.TASK
KIND_BY_SUFFIX = {".map": MAP, ".rm": ROADMAP, ".xml": PROGRAM, ".task": TASK}


@cache
def xsd(kind: DocumentKind) -> xmlschema.XMLSchema10:
    return xmlschema.XMLSchema10(str(schema_path(kind)))


def xmlschema_valid(kind: DocumentKind, data: bytes) -> bool:
    root = etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True))
    return etree.QName(root).localname == kind.value and xsd(kind).is_valid(data.decode("utf-8"))


def check(kind: DocumentKind, xml: str | bytes, *, valid: bool) -> None:
    """Both engines agree with `valid`; an invalid document raises DocumentError (a ValueError)."""
    data = xml.encode("utf-8") if isinstance(xml, str) else xml
    if valid:
        validate_document(kind, data)
    else:
        with pytest.raises(DocumentError):
            validate_document(kind, data)
    assert xmlschema_valid(kind, data) is valid


def error_of(kind: DocumentKind, data: bytes) -> str:
    with pytest.raises(DocumentError) as info:
        validate_document(kind, data)
    return str(info.value)


# ---------------------------------------------------------------- fixtures

VALID_FIXTURES = [
    (MAP, OFFICE_MAP),
    (ROADMAP, OFFICE_RM),
    (PROGRAM, FIXTURES / "programs" / "patrol.xml"),
    (PROGRAM, FIXTURES / "programs" / "every_element.xml"),
]

# file -> a fragment the DocumentError message must contain (it names the problem)
INVALID_FIXTURES = {
    "wrong_root.map": "root element is <roadmap>, expected <map>",
    "missing_point.map": "Element 'line': Missing child element(s)",
    "bad_number.rm": "'1e3' is not a valid value",
    "dangling_edge.rm": "'nowhere'",
    "unknown_element.xml": "Element 'fly': This element is not expected",
    "bad_digitalout.task": "attribute 'D3'",
    "billion_laughs.map": "entity declarations are not allowed",
    "xxe_system.map": "entity declarations are not allowed",
}
ENTITY_FIXTURES = {"billion_laughs.map", "xxe_system.map"}


@pytest.mark.parametrize(("kind", "path"), VALID_FIXTURES, ids=lambda v: getattr(v, "name", str(v)))
def test_valid_fixture(kind: DocumentKind, path: Path) -> None:
    data = path.read_bytes()
    tree = validate_document(kind, data)
    assert tree.getroot().tag == kind.value
    assert detect_kind(data) is kind
    xsd(kind).validate(str(path))  # raises with the reason if the other engine disagrees


def test_invalid_fixture_table_is_complete() -> None:
    assert sorted(p.name for p in (FIXTURES / "invalid").iterdir()) == sorted(INVALID_FIXTURES)


@pytest.mark.parametrize("name", sorted(INVALID_FIXTURES))
def test_invalid_fixture(name: str) -> None:
    path = FIXTURES / "invalid" / name
    data = path.read_bytes()
    assert re.search(rb"^<!-- invalid [^\n]*-->$", data, re.MULTILINE), "needs a one-line comment saying why"
    kind = KIND_BY_SUFFIX[path.suffix]
    message = error_of(kind, data)
    assert INVALID_FIXTURES[name] in message
    assert "\n" not in message
    if name not in ENTITY_FIXTURES:
        assert re.search(r"line \d+", message)
        assert not xmlschema_valid(kind, data)


def test_standalone_task_document() -> None:
    task = '<task name="t" version="1.0"><label name="a"/><wait><delay amount="10"/></wait><goto label="a"/></task>'
    check(TASK, task, valid=True)
    check(PROGRAM, f"<program>{task}</program>", valid=True)
    with pytest.raises(DocumentError, match="expected <program>"):
        validate_document(PROGRAM, task.encode())  # program.xsd includes <task> globally: root checked


def schema_vocabulary(kind: DocumentKind) -> dict[str, set[str]]:
    """Element local name -> attribute names, for every element the schema can reach from its root."""
    seen: dict[str, set[str]] = {}

    def walk(element: xmlschema.XsdElement) -> None:
        seen.setdefault(element.local_name, set()).update(str(a) for a in element.attributes)
        for child in element.iterchildren():
            if child.local_name not in seen:
                walk(child)

    walk(xsd(kind).elements[kind.value])
    return seen


def document_vocabulary(trees: Iterable[etree._ElementTree]) -> dict[str, set[str]]:
    used: dict[str, set[str]] = {}
    for tree in trees:
        for element in tree.iter(etree.Element):
            used.setdefault(element.tag, set()).update(element.attrib)
    return used


def test_every_element_program_uses_every_element_and_attribute() -> None:
    tree = validate_document(PROGRAM, (FIXTURES / "programs" / "every_element.xml").read_bytes())
    assert document_vocabulary([tree]) == schema_vocabulary(PROGRAM)


# every element of guide 6.5, by document (the schemas may add only spelling variants, E-XML-003/004)
GUIDE_ELEMENTS = {
    MAP: {
        "map",
        "layer",
        "circle",
        "line",
        "auxline",
        "linemapped",
        "auxlinemapped",
        "reflmark",
        "prohibit",
        "workarea",
        "hiddenpolygon",
        "center",
        "radius",
        "point",
        "hiddenlabel",
    },
    ROADMAP: {"roadmap", "stations", "edges", "station", "edge", "point"},
    PROGRAM: {
        "program",
        "task",
        "ioevent",
        "digitalout",
        "goto",
        "label",
        "load",
        "log",
        "motion",
        "settarget",
        "coord",
        "station",
        "moveto",
        "trackedperson",
        "trackedball",
        "trackedmovingobject",
        "chargingstation",
        "parameter",
        "set",
        "surveillance",
        "grab",
        "movecamera",
        "audio",
        "speak",
        "play",
        "turnhead",
        "wait",
        "collision",
        "movingobject",
        "person",
        "ball",
        "lostlocalization",
        "target",
        "infrared",
        "radar",
        "date",
        "delay",
        "userevent",
        "random",
        "batterycharge",
    },
}
SPELLING_VARIANTS = {ROADMAP: {"points"}, PROGRAM: {"movingobjects", "lostlocalisation"}, MAP: set()}


@pytest.mark.parametrize("kind", [MAP, ROADMAP, PROGRAM])
def test_schemas_declare_every_element_of_the_guide(kind: DocumentKind) -> None:
    assert set(schema_vocabulary(kind)) == GUIDE_ELEMENTS[kind] | SPELLING_VARIANTS[kind]


def test_every_schema_element_is_documented_from_the_guide() -> None:
    ns = {"xs": "http://www.w3.org/2001/XMLSchema"}
    for path in SCHEMA_DIR.glob("*.xsd"):
        tree = etree.parse(str(path))
        for decl in tree.iterfind(".//xs:element[@name]", ns):
            documented = decl.find("xs:annotation/xs:documentation", ns) is not None
            typed = decl.get("type")
            if not documented and typed:  # documented on its named complexType
                documented = tree.find(f".//xs:complexType[@name='{typed}']/xs:annotation", ns) is not None
            assert documented, f"{path.name}: <{decl.get('name')}> has no xs:documentation"


# ---------------------------------------------------------------- guide ambiguities (spec/errata/xml.yaml)

LINE = '<line><point x="0" y="0"/><point x="1000" y="0"/></line>'
STATIONS = (
    '<stations><station id="a"><point x="0" y="0"/></station><station id="b"><point x="9" y="9"/></station></stations>'
)


@pytest.mark.parametrize("attrs", ['Version="1.0"', 'version="1.0"', 'Version="1" version="2"', ""])
@pytest.mark.parametrize("kind", list(DocumentKind))
def test_version_attribute_either_case(kind: DocumentKind, attrs: str) -> None:  # E-XML-001, E-XML-002
    body = {MAP: "", ROADMAP: "<stations/><edges/>", PROGRAM: "<task/>", TASK: ""}[kind]
    check(kind, f"<{kind.value} {attrs}>{body}</{kind.value}>", valid=True)


@pytest.mark.parametrize(
    ("edge_body", "valid"),
    [
        ('<points><point x="1" y="2"/><point x="3" y="4"/></points>', True),
        ("<points/>", True),
        ('<point x="1" y="2"/><point x="3" y="4"/>', True),
        ('<point x="1" y="2"/>', True),
        ("", True),
        ('<points/><point x="1" y="2"/>', False),  # not both forms
        ("<points/><points/>", False),
        ("<points><points/></points>", False),
    ],
)
def test_edge_points_with_and_without_wrapper(edge_body: str, valid: bool) -> None:  # E-XML-003
    roadmap = f'<roadmap>{STATIONS}<edges><edge startstation="a" endstation="b">{edge_body}</edge></edges></roadmap>'
    check(ROADMAP, roadmap, valid=valid)


@pytest.mark.parametrize("child", ["movingobject", "movingobjects", "lostlocalization", "lostlocalisation"])
def test_wait_child_spellings(child: str) -> None:  # E-XML-004
    check(TASK, f'<task><wait for="{child}" timeout="100"><{child}/></wait></task>', valid=True)


@pytest.mark.parametrize(
    ("wait", "valid"),
    [
        ('<wait for="delay"><delay amount="1.5"/></wait>', True),  # E-XML-008: `for` accepted
        ('<wait timeout="500"/>', True),  # E-XML-019: empty wait = timeout only
        ("<wait><collision/><person/></wait>", False),  # E-XML-019: at most one event
        ('<wait timeout="-1"><ball/></wait>', False),  # E-XML-009: ms, not negative
        ('<wait for="a b"><ball/></wait>', False),  # NMTOKEN
        ("<wait><movingObject/></wait>", False),
        ('<wait><random min="10" max="20"/></wait>', True),
        ('<wait><date hour="24"/></wait>', False),
    ],
)
def test_wait_variants(wait: str, valid: bool) -> None:
    check(TASK, f"<task>{wait}</task>", valid=valid)


LAYER_CHILDREN = [
    '<workarea><point x="0" y="0"/><point x="9" y="0"/><point x="9" y="9"/></workarea>',
    '<circle><center x="5" y="5"/><radius r="1"/></circle>',
    LINE,
    LINE.replace("line", "auxline"),
    LINE.replace("line", "linemapped"),
    LINE.replace("line", "auxlinemapped"),
    '<reflmark><point x="1" y="1"/><point x="1" y="2"/></reflmark>',
    '<prohibit><point x="1" y="1"/><point x="2" y="2"/></prohibit>',
    '<hiddenpolygon><point x="1" y="1"/><point x="2" y="2"/><point x="3" y="1"/></hiddenpolygon>',
    '<hiddenlabel text="Room 1"><point x="1" y="1"/></hiddenlabel>',
]


@pytest.mark.parametrize("order", [0, 1, 2, 3])
def test_layer_children_in_any_order_and_number(order: int) -> None:  # E-XML-005
    children = list(reversed(LAYER_CHILDREN)) if order == 1 else list(LAYER_CHILDREN)
    if order == 2:
        children = children[1::2] + children[::2] + children  # interleaved, everything twice
    if order == 3:
        children = [LAYER_CHILDREN[1], LAYER_CHILDREN[0], LAYER_CHILDREN[0]]  # workarea after, twice
    check(MAP, f'<map><layer index="0">{"".join(children)}</layer><layer/></map>', valid=True)


@pytest.mark.parametrize(
    ("value", "valid"),
    [
        ("12", True),
        ("-12.5", True),
        ("+0.25", True),
        (".5", True),
        ("1e3", False),
        ("12,5", False),
        ("0x10", False),
        ("abc", False),
        ("", False),
        ("NaN", False),
        ("INF", False),
    ],
)
def test_coordinates_are_decimal_numbers(value: str, valid: bool) -> None:  # E-XML-006, E-XML-007
    check(MAP, f'<map><layer><line><point x="{value}" y="0"/><point x="1" y="1"/></line></layer></map>', valid=valid)
    station = f'<station id="s" angle="{value}"><point x="0" y="0"/></station>'
    check(ROADMAP, f"<roadmap><stations>{station}</stations><edges/></roadmap>", valid=valid)
    check(TASK, f'<task><turnhead angle="{value}"/></task>', valid=valid)


@pytest.mark.parametrize(
    ("coord", "angle", "coord_ok", "angle_ok"),
    [
        ("2147483647", "2147483", True, True),
        ("-2147483647", "-2147483", True, True),
        ("2147483648", "0", False, True),
        ("1" + "0" * 400, "0", False, True),  # a double overflows to infinity: a fuzzer's map broke the platform
        ("0", "2147484", True, False),
    ],
)
def test_coordinates_and_angles_stay_within_what_the_telegrams_carry(
    coord: str, angle: str, coord_ok: bool, angle_ok: bool
) -> None:  # E-XML-025
    check(MAP, f'<map><layer><line><point x="{coord}" y="0"/><point x="1" y="1"/></line></layer></map>', valid=coord_ok)
    station = f'<station id="s" angle="{angle}"><point x="{coord}" y="0"/></station>'
    check(ROADMAP, f"<roadmap><stations>{station}</stations><edges/></roadmap>", valid=coord_ok and angle_ok)
    check(
        TASK,
        f'<task><turnhead angle="{angle}"/><motion><settarget><coord x="{coord}" y="0" angle="0"/>'
        f"</settarget></motion></task>",
        valid=coord_ok and angle_ok,
    )


@pytest.mark.parametrize(
    ("condition", "valid"),
    [
        ("true", True),
        ("false", True),
        ("1", True),
        ("0", True),
        ("DI3==1", True),
        ("DI16!=0", True),
        ("DO12==1", True),
        ("param:MaxTransVel==600", True),
        ("param:FlashlightEnabled!=true", True),
        (" DI3==1 ", True),
        ("DI17==1", False),
        ("DO13==1", False),
        ("DI3 == 1", False),
        ("DI3=1", False),
        ("yes", False),
        ("", False),
        ("param:==1", False),
        ("DI3==", False),
    ],
)
def test_goto_condition_language(condition: str, valid: bool) -> None:  # E-XML-013
    check(TASK, f'<task><goto label="x" condition="{condition}"/><label name="x"/></task>', valid=valid)


@pytest.mark.parametrize(
    ("doc", "valid"),
    [
        ('<hiddenlabel text="Büro 3 – Süd"><point x="0" y="0"/></hiddenlabel>', True),  # E-XML-010
        ('<hiddenlabel>Kitchen<point x="0" y="0"/></hiddenlabel>', True),
        ("<hiddenlabel/>", False),
        ('<reflmark><point x="0" y="0"/></reflmark>', True),  # E-XML-016
        ('<reflmark><point x="0" y="0"/><point x="0" y="0"/><point x="0" y="0"/></reflmark>', False),
        ('<circle><radius r="1"/><center x="0" y="0"/></circle>', False),
        ('<circle><center x="0" y="0"/><radius r="-1"/></circle>', False),
        ('<prohibit><point x="0" y="0"/></prohibit>', False),
    ],
)
def test_map_element_variants(doc: str, valid: bool) -> None:
    check(MAP, f"<map><layer>{doc}</layer></map>", valid=valid)


@pytest.mark.parametrize(
    ("doc", "valid"),
    [
        ('<motion stop="1"/>', True),  # E-XML-017, E-XML-020
        ('<motion stop="true"/>', True),
        ('<motion stop="yes"/>', False),
        ('<surveillance><grab filename="f" grabscan="1" grabimage="false"/></surveillance>', True),
        ("<ioevent><digitalout/></ioevent>", True),  # E-XML-023
        ('<ioevent><digitalout D12="+1"/></ioevent>', False),
        ('<ioevent><digitalout D13="1"/></ioevent>', False),
        ("<audio/>", False),
        ('<motion><settarget><coord x="1" y="2"/><station name="A"/></settarget></motion>', False),
        ('<motion><settarget><station name="Room 1"/></settarget></motion>', True),
    ],
)
def test_task_element_variants(doc: str, valid: bool) -> None:
    check(TASK, f"<task>{doc}</task>", valid=valid)


def test_station_ids_are_xml_ids() -> None:  # E-XML-014
    station = '<station id="{}"><point x="0" y="0"/></station>'
    check(ROADMAP, f"<roadmap><stations>{station.format('1')}</stations><edges/></roadmap>", valid=False)
    dup = station.format("a") * 2
    check(ROADMAP, f"<roadmap><stations>{dup}</stations><edges/></roadmap>", valid=False)
    upper_x = '<station id="a"><point X="0" y="0"/></station>'  # E-XML-018
    check(ROADMAP, f"<roadmap><stations>{upper_x}</stations><edges/></roadmap>", valid=False)


# ---------------------------------------------------------------- safe parsing (E-XML-011, 012, 021)

LAUGHS = (
    '<?xml version="1.0" encoding="UTF-16"?>\n<!DOCTYPE map [<!ENTITY a "aaaaaaaaaa">'
    '<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">]>\n<map><layer><hiddenlabel text="&b;"><point x="0" y="0"/>'
    "</hiddenlabel></layer></map>"
)


def test_entity_declarations_refused_in_any_encoding() -> None:
    data = LAUGHS.encode("utf-16")  # invisible to a byte scan for "<!ENTITY"
    assert b"<!ENTITY" not in data
    assert error_of(MAP, data).endswith("entity declarations are not allowed")
    parameter_entity = b'<!DOCTYPE map [<!ENTITY % x SYSTEM "file:///etc/passwd"> %x;]><map/>'
    assert "entity declarations are not allowed" in error_of(MAP, parameter_entity)


def test_doctype_without_entities_is_allowed_and_never_fetched() -> None:
    doctypes = [
        '<!DOCTYPE map SYSTEM "http://127.0.0.1:9/map.dtd">',
        '<!DOCTYPE map SYSTEM "/nonexistent/map.dtd">',
        "<!DOCTYPE map [<!ELEMENT map ANY>]>",
    ]
    for doctype in doctypes:
        tree = validate_document(MAP, f'<?xml version="1.0"?>\n{doctype}\n<map Version="1"/>'.encode())
        assert tree.getroot().tag == "map"


def test_undeclared_entity_reference_is_not_well_formed() -> None:
    message = error_of(MAP, b"<map>\n<layer>&secret;</layer></map>")
    assert "not well-formed" in message
    assert "line 2" in message


def test_encoding_declared_or_utf8() -> None:
    label = '<map><layer><hiddenlabel text="Büro"><point x="0" y="0"/></hiddenlabel></layer></map>'
    tree = validate_document(MAP, label.encode("utf-8"))
    assert tree.find(".//hiddenlabel").get("text") == "Büro"
    latin1 = ('<?xml version="1.0" encoding="ISO-8859-1"?>' + label).encode("latin-1")
    assert validate_document(MAP, latin1).find(".//hiddenlabel").get("text") == "Büro"
    assert "not well-formed" in error_of(MAP, label.encode("latin-1"))  # undeclared: UTF-8, and invalid


def test_size_limit() -> None:
    doc = b"<map>" + b"<layer/>" * 100 + b"</map>"
    validate_document(MAP, doc)
    assert "over the limit of 100" in error_of_sized(doc, 100)
    assert DEFAULT_MAX_SIZE == 8 * 1024 * 1024
    big = b"<map>" + b" " * DEFAULT_MAX_SIZE + b"</map>"
    assert "over the limit" in error_of(MAP, big)


def error_of_sized(data: bytes, max_size: int) -> str:
    with pytest.raises(DocumentError) as info:
        validate_document(MAP, data, max_size=max_size)
    return str(info.value)


def test_depth_limit() -> None:
    deep = b"<map>" + b"<layer>" * MAX_DEPTH + b"</layer>" * MAX_DEPTH + b"</map>"
    assert f"over the limit of {MAX_DEPTH}" in error_of(MAP, deep)


def test_detect_kind() -> None:
    for kind in DocumentKind:
        assert detect_kind(f"<!-- c --><{kind.value}/>".encode()) is kind
    with pytest.raises(DocumentError, match="unknown root element <svg>"):
        detect_kind(b"<svg/>")
    with pytest.raises(DocumentError, match="unknown root element"):
        detect_kind(b'<map xmlns="urn:x"/>')


@settings(max_examples=150, deadline=None)
@given(
    st.binary(max_size=200)
    | st.builds(lambda a, b: a + b, st.sampled_from([b"<map>", b"<task>", b"<?xml"]), st.binary(max_size=60))
)
def test_any_bytes_parse_or_raise_document_error(data: bytes) -> None:
    for kind in (MAP, TASK):
        with contextlib.suppress(DocumentError):  # anything else fails the test
            validate_document(kind, data)


# ---------------------------------------------------------------- random maps (Hypothesis)

coord = st.integers(-50000, 50000).map(str) | st.decimals(-1e5, 1e5, places=2, allow_nan=False).map(str)
points = st.builds(lambda x, y: ("point", {"x": x, "y": y}, []), coord, coord)


def pts(n_min: int, n_max: int) -> st.SearchStrategy[list[tuple[str, dict[str, str], list[object]]]]:
    return st.lists(points, min_size=n_min, max_size=n_max)


# (name, minimum number of children): removing one child below that makes the document invalid
MAP_ELEMENTS: dict[str, tuple[st.SearchStrategy[list[object]], int]] = {
    "workarea": (pts(2, 5), 2),
    "prohibit": (pts(2, 5), 2),
    "hiddenpolygon": (pts(3, 6), 3),
    "line": (pts(2, 2), 2),
    "auxline": (pts(2, 2), 2),
    "linemapped": (pts(2, 2), 2),
    "auxlinemapped": (pts(2, 2), 2),
    "reflmark": (pts(1, 2), 1),
    "hiddenlabel": (pts(1, 1), 1),
    "circle": (
        st.builds(
            lambda c, r: [("center", {"x": c[1]["x"], "y": c[1]["y"]}, []), ("radius", {"r": r}, [])],
            points,
            st.integers(0, 5000).map(str),
        ),
        2,
    ),
}
map_element = st.sampled_from(sorted(MAP_ELEMENTS)).flatmap(
    lambda name: MAP_ELEMENTS[name][0].map(lambda children: (name, {}, children))
)
layers = st.lists(st.lists(map_element, max_size=8), max_size=4)


def build_map(layer_list: list[list[tuple[str, dict[str, str], list[object]]]]) -> etree._Element:
    root = etree.Element("map", Version="1.0")

    def add(parent: etree._Element, node: tuple[str, dict[str, str], list[object]]) -> None:
        name, attrs, children = node
        element = etree.SubElement(parent, name, attrs)
        if name == "hiddenlabel":
            element.set("text", "Room")
        for child in children:
            add(element, child)  # type: ignore[arg-type]

    for index, elements in enumerate(layer_list):
        layer = etree.SubElement(root, "layer", index=str(index))
        for node in elements:
            add(layer, node)
    return root


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(layers, st.data())
def test_random_maps_validate_and_break_when_a_required_child_goes(
    layer_list: list[list[tuple[str, dict[str, str], list[object]]]], data: st.DataObject
) -> None:
    root = build_map(layer_list)
    check(MAP, etree.tostring(root), valid=True)
    breakable = [e for e in root.iter(*MAP_ELEMENTS) if e.getparent().tag == "layer"]
    if not breakable:
        return
    victim = data.draw(st.sampled_from(breakable))
    minimum = MAP_ELEMENTS[victim.tag][1]
    while len(victim) >= minimum:  # delete required children until one too few remain
        victim.remove(victim[data.draw(st.integers(0, len(victim) - 1))])
    check(MAP, etree.tostring(root), valid=False)


# ---------------------------------------------------------------- the office floor

CLEARANCE = 300.0  # mm each side of a roadmap edge: a 600 mm wide platform fits
Pt = tuple[float, float]


def _xy(element: etree._Element) -> Pt:
    return float(element.get("x")), float(element.get("y"))


def _cross(o: Pt, a: Pt, b: Pt) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def segments_intersect(p1: Pt, p2: Pt, q1: Pt, q2: Pt) -> bool:
    d1, d2, d3, d4 = _cross(q1, q2, p1), _cross(q1, q2, p2), _cross(p1, p2, q1), _cross(p1, p2, q2)
    return (d1 * d2 < 0) and (d3 * d4 < 0)


def point_segment_distance(p: Pt, a: Pt, b: Pt) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2))
    return math.dist(p, (a[0] + t * dx, a[1] + t * dy))


def segment_distance(p1: Pt, p2: Pt, q1: Pt, q2: Pt) -> float:
    if segments_intersect(p1, p2, q1, q2):
        return 0.0
    return min(
        point_segment_distance(p1, q1, q2),
        point_segment_distance(p2, q1, q2),
        point_segment_distance(q1, p1, p2),
        point_segment_distance(q2, p1, p2),
    )


def point_in_polygon(p: Pt, polygon: list[Pt]) -> bool:
    inside = False
    for a, b in zip(polygon, polygon[1:] + polygon[:1], strict=True):
        if (a[1] > p[1]) != (b[1] > p[1]) and p[0] < a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]):
            inside = not inside
    return inside


@cache
def office() -> tuple[etree._ElementTree, etree._ElementTree]:
    return validate_document(MAP, OFFICE_MAP.read_bytes()), validate_document(ROADMAP, OFFICE_RM.read_bytes())


def obstacles() -> tuple[list[tuple[Pt, Pt]], list[tuple[Pt, float]], list[list[Pt]]]:
    office_map = office()[0]
    walls = [(_xy(a), _xy(b)) for a, b in (line.findall("point") for line in office_map.iter("line"))]
    circles = [(_xy(c.find("center")), float(c.find("radius").get("r"))) for c in office_map.iter("circle")]
    prohibits = [[_xy(p) for p in zone.findall("point")] for zone in office_map.iter("prohibit")]
    return walls, circles, prohibits


def roadmap_paths() -> list[tuple[str, str, list[Pt]]]:
    roadmap = office()[1]
    at = {s.get("id"): _xy(s.find("point")) for s in roadmap.iter("station")}
    return [
        (
            e.get("startstation"),
            e.get("endstation"),
            [at[e.get("startstation")], *(_xy(p) for p in e.iter("point")), at[e.get("endstation")]],
        )
        for e in roadmap.iter("edge")
    ]


def test_office_map_is_a_30_by_20_m_floor() -> None:
    office_map = office()[0]
    xs = [float(p.get("x")) for p in office_map.iter("point", "center")]
    ys = [float(p.get("y")) for p in office_map.iter("point", "center")]
    assert max(xs) - min(xs) >= 30000 and max(ys) - min(ys) >= 20000
    for name in ("workarea", "line", "circle", "reflmark", "prohibit", "hiddenlabel"):
        assert office_map.find(f".//{name}") is not None, name
    assert len(office_map.findall(".//hiddenlabel")) >= 7  # six or more rooms and the corridor


def test_office_roadmap_edges_clear_the_walls_and_the_graph_is_connected() -> None:
    walls, circles, prohibits = obstacles()
    roadmap = office()[1]
    stations = {s.get("id"): s.get("name") for s in roadmap.iter("station")}
    assert len(stations) >= 8 and "Charging" in stations.values()
    paths = roadmap_paths()
    for start, end, path in paths:
        for a, b in itertools.pairwise(path):
            for w1, w2 in walls:
                assert segment_distance(a, b, w1, w2) >= CLEARANCE, (start, end, (w1, w2))
            for centre, radius in circles:
                assert point_segment_distance(centre, a, b) >= radius + CLEARANCE, (start, end, centre)
            for zone in prohibits:
                assert not point_in_polygon(a, zone)
                for z1, z2 in zip(zone, zone[1:] + zone[:1], strict=True):
                    assert segment_distance(a, b, z1, z2) >= CLEARANCE, (start, end, "prohibit")
    neighbours: dict[str, set[str]] = {s: set() for s in stations}
    for start, end, _ in paths:
        neighbours[start].add(end)
        neighbours[end].add(start)
    reached, todo = set(), [next(iter(stations))]
    while todo:
        station = todo.pop()
        if station not in reached:
            reached.add(station)
            todo.extend(neighbours[station])
    assert reached == set(stations)


def test_office_files_are_not_stale() -> None:
    spec = importlib.util.spec_from_file_location("make_office", FIXTURES / "maps" / "make_office.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up while the class is built
    try:
        spec.loader.exec_module(module)
        assert module.main(["--check"]) == 0, "run python fixtures/maps/make_office.py"
    finally:
        del sys.modules[spec.name]


def test_start_pose_is_in_the_corridor() -> None:
    lines = (FIXTURES / "start_pose.dat").read_text(encoding="utf-8").splitlines()
    assert lines[0].startswith("#")
    values = [line.split() for line in lines if line.strip() and not line.startswith("#")]
    assert len(values) == 1 and len(values[0]) == 3
    x, y, angle = map(float, values[0])
    assert -math.pi <= angle <= math.pi  # radians
    walls, _, _ = obstacles()
    assert min(point_segment_distance((x, y), a, b) for a, b in walls) >= 600
    workarea = [_xy(p) for p in office()[0].find(".//workarea").findall("point")]
    assert point_in_polygon((x, y), workarea)


# ---------------------------------------------------------------- errata register


def test_errata_register() -> None:
    entries = yaml.safe_load(ERRATA.read_text(encoding="utf-8"))
    keys = {"id", "section", "guide", "problem", "decision", "reason", "alternatives", "level"}
    ids = [entry["id"] for entry in entries]
    assert ids == [f"E-XML-{n:03d}" for n in range(1, len(ids) + 1)]
    for entry in entries:
        assert set(entry) == keys, entry["id"]
        assert entry["level"] in {"MUST", "SHOULD", "MAY"}
        assert entry["alternatives"], entry["id"]
        for alternative in entry["alternatives"]:
            assert set(alternative) == {"reading", "original_profile"}
            assert alternative["original_profile"] in {"accept", "reject"}
    cited = set()
    for path in [*SCHEMA_DIR.glob("*.xsd"), ROOT / "spec" / "documents.py"]:
        cited |= set(re.findall(r"E-XML-\d{3}", path.read_text(encoding="utf-8")))
    assert cited <= set(ids)
