"""Hostile XML documents for CMD_SET_MAP, CMD_SET_ROADMAP and CMD_SET_PROGRAM (guide 6.5).

Rules:
- Every attack is a function ``(kind, rng) -> bytes`` in ``ATTACKS`` (a table, not a chain of ifs); ``kind``
  is "map", "roadmap" or "program".
- External references point only at 127.0.0.1 (port 9, discard, normally closed) or at a file path: a target
  that fetches them reaches nothing outside this machine.
- Sizes are bounded (the largest document is ``BIG_POINTS`` points, about 7 MB, under the 8 MB document limit
  of erratum E-XML-021; "a million points" is the one that goes over it on purpose). Big documents are built
  once per process and cached.
- "absurd" documents are schema-valid: they must pass ``pltf.spec.documents.validate_document`` (a test checks),
  so they reach the target's geometry, planning and task interpreter rather than its validator.
"""

from __future__ import annotations

import functools
import random
from collections.abc import Callable

DECL = b'<?xml version="1.0" encoding="UTF-8"?>\n'
LOCAL_URL = b"http://127.0.0.1:9/"
ROOT = {"map": b'<map Version="1.0">', "roadmap": b'<roadmap Version="1.0">', "program": b'<program version="1.0">'}
END = {"map": b"</map>", "roadmap": b"</roadmap>", "program": b"</program>"}
BIG_POINTS = 300_000
MILLION = 1_000_000
HUGE_DIGITS = b"9" * 5000  # an xs:decimal no float or bounded int can hold (out of range since E-XML-025)
MAX_COORD = b"2147483647"  # the edges of the ranges documents may use (E-XML-025: what the telegrams carry)
MAX_ANGLE = b"2147483"


def _doc(kind: str, body: bytes, doctype: bytes = b"") -> bytes:
    return DECL + doctype + ROOT[kind] + body + END[kind]


def _carrier(kind: str, text: bytes) -> bytes:
    """A minimal element of ``kind`` that carries ``text`` in an attribute (for entity references)."""
    if kind == "map":
        return b'<layer index="0"><hiddenlabel text="' + text + b'"><point x="0" y="0"/></hiddenlabel></layer>'
    if kind == "roadmap":
        return b'<stations><station id="s" name="' + text + b'"><point x="0" y="0"/></station></stations><edges/>'
    return b'<task name="t"><log type="info" message="' + text + b'"/></task>'


def billion_laughs(kind: str, rng: random.Random) -> bytes:
    levels = [b'<!ENTITY lol0 "lol">']
    for i in range(1, 10):
        levels.append(b'<!ENTITY lol%d "%s">' % (i, (b"&lol%d;" % (i - 1)) * 10))
    return _doc(kind, _carrier(kind, b"&lol9;"), b"<!DOCTYPE " + kind.encode() + b" [" + b"".join(levels) + b"]>")


def quadratic_blowup(kind: str, rng: random.Random) -> bytes:
    return _quadratic_blowup(kind)


@functools.cache
def _quadratic_blowup(kind: str) -> bytes:
    ent = b"<!DOCTYPE " + kind.encode() + b' [<!ENTITY a "' + b"A" * 20_000 + b'">]>'
    return _doc(kind, _carrier(kind, b"&a;" * 2_000), ent)


def xxe_file(kind: str, rng: random.Random) -> bytes:
    path = rng.choice([b"file:///etc/passwd", b"/etc/hostname", b"file:///dev/zero", b"file:///proc/self/environ"])
    ent = b"<!DOCTYPE " + kind.encode() + b' [<!ENTITY x SYSTEM "' + path + b'">]>'
    return _doc(kind, _carrier(kind, b"&x;"), ent)


def xxe_network(kind: str, rng: random.Random) -> bytes:
    ent = b"<!DOCTYPE " + kind.encode() + b' [<!ENTITY x SYSTEM "' + LOCAL_URL + b'x.xml">]>'
    return _doc(kind, _carrier(kind, b"&x;"), ent)


def xxe_parameter(kind: str, rng: random.Random) -> bytes:
    ent = b"<!DOCTYPE " + kind.encode() + b' [<!ENTITY % p SYSTEM "' + LOCAL_URL + b'p.dtd"> %p;]>'
    return _doc(kind, _carrier(kind, b"x"), ent)


def external_dtd(kind: str, rng: random.Random) -> bytes:
    """A DOCTYPE without entity declarations whose external subset a careless parser would fetch."""
    return _doc(kind, _carrier(kind, b"x"), b"<!DOCTYPE " + kind.encode() + b' SYSTEM "' + LOCAL_URL + b'd.dtd">')


def xinclude(kind: str, rng: random.Random) -> bytes:
    inc = b'<xi:include xmlns:xi="http://www.w3.org/2001/XInclude" href="file:///etc/passwd" parse="text"/>'
    return _doc(kind, inc + _carrier(kind, b"x"))


def deep_nesting(kind: str, rng: random.Random) -> bytes:
    return _deep(kind, rng.choice([65, 1_000, 100_000]))


@functools.cache
def _deep(kind: str, depth: int) -> bytes:
    return _doc(kind, b"<layer>" * depth + b"</layer>" * depth)


def huge_attribute(kind: str, rng: random.Random) -> bytes:
    return _huge_attribute(kind, rng.choices([70_000, 1 << 20, 6 << 20], [0.85, 0.12, 0.03])[0])


@functools.cache
def _huge_attribute(kind: str, size: int) -> bytes:
    return _doc(kind, _carrier(kind, b"A" * size))


def many_attributes(kind: str, rng: random.Random) -> bytes:
    return _many_attributes(kind)


@functools.cache
def _many_attributes(kind: str) -> bytes:
    attrs = b" ".join(b'a%d="%d"' % (i, i) for i in range(20_000))
    return _doc(kind, b"<layer " + attrs + b"/>")


def bad_encoding(kind: str, rng: random.Random) -> bytes:
    head = rng.choice(
        [
            b'<?xml version="1.0" encoding="UTF-16"?>',
            b'<?xml version="1.0" encoding="x-nonexistent"?>',
            b'<?xml version="1.0" encoding="UTF-8"?>\xff\xfe\xc3\x28',
            b"\xef\xbb\xbf\xef\xbb\xbf",
            b"\x00<\x00?\x00x\x00m\x00l",
        ]
    )
    return head + ROOT[kind] + _carrier(kind, b"\xc3\x28\xed\xa0\x80") + END[kind]


def _polygon(points: list[tuple[int, int]]) -> bytes:
    return b"".join(b'<point x="%d" y="%d"/>' % p for p in points)


@functools.cache
def _big_map(points: int) -> bytes:
    pts = [(i % 1000 * 7, (i * 7919) % 100_000) for i in range(points)]
    return _doc("map", b'<layer index="0"><workarea>' + _polygon(pts) + b"</workarea></layer>")


def million_points(kind: str, rng: random.Random) -> bytes:
    """Schema-valid but absurd: a map whose work area has ``BIG_POINTS`` (or a million) points."""
    return _big_map(MILLION if rng.random() < 0.1 else BIG_POINTS)


def absurd_map(kind: str, rng: random.Random) -> bytes:
    return _absurd_map(rng.randrange(6))


@functools.cache
def _absurd_map(choice: int) -> bytes:
    if choice == 0:  # self-intersecting bow tie as work area and prohibited area
        bow = _polygon([(0, 0), (10_000, 10_000), (10_000, 0), (0, 10_000)])
        body = b"<workarea>" + bow + b"</workarea><prohibit>" + bow + b"</prohibit>"
    elif choice == 1:  # degenerate polygons: all points equal, collinear
        body = b"<workarea>" + _polygon([(5, 5)] * 50) + b"</workarea><prohibit>" + _polygon([(0, 0), (1, 1), (2, 2)])
        body += b"</prohibit>"
    elif choice == 2:  # zero-length lines and a zero/huge radius circle
        body = b"<line>" + _polygon([(1, 1), (1, 1)]) + b'</line><circle><center x="0" y="0"/><radius r="0"/></circle>'
        body += b'<circle><center x="0" y="0"/><radius r="' + MAX_COORD + b'"/></circle>'
    elif choice == 3:  # coordinates at the edges of the range, a line across all of it
        big = b'<point x="' + MAX_COORD + b'" y="-' + MAX_COORD + b'"/>'
        body = b"<line>" + big + b'<point x="-' + MAX_COORD + b'" y="' + MAX_COORD + b'"/></line>'
    elif choice == 4:  # 32-bit extremes and sub-micron decimals
        body = b"<line>" + _polygon([(2**31 - 1, -(2**31 - 1)), (-(2**31 - 1), 2**31 - 1)]) + b"</line>"
        body += b'<line><point x="0.' + b"0" * 3000 + b'1" y="-0.0"/><point x="1000.000" y="+1"/></line>'
    else:  # many layers with the same index, the robot far outside its work area
        body = b"".join(
            b'<layer index="0"><line>' + _polygon([(i, i), (i + 1, i)]) + b"</line></layer>" for i in range(200)
        )
        return _doc("map", body)
    return _doc("map", b'<layer index="0">' + body + b"</layer>")


def absurd_roadmap(kind: str, rng: random.Random) -> bytes:
    # the complete graph (2) and the long polyline (4) cost a target ~0.1 s each: drawn a tenth as often
    return _absurd_roadmap(rng.choices(range(5), (1.0, 1.0, 0.1, 1.0, 0.1))[0])


@functools.cache
def _absurd_roadmap(choice: int) -> bytes:
    st = b'<station id="s%d" name="S%d" angle="%s"><point x="%s" y="0"/></station>'
    if choice == 0:  # stations without any edge: all unreachable
        stations = b"".join(st % (i, i, b"0", b"%d" % (i * 1000)) for i in range(50))
        return _doc("roadmap", b"<stations>" + stations + b"</stations><edges/>")
    if choice == 1:  # self loops and a cycle, no path to the last station
        stations = b"".join(st % (i, i, b"0", b"%d" % i) for i in range(4))
        edges = b'<edge startstation="s0" endstation="s0"/><edge startstation="s1" endstation="s2"/>'
        edges += b'<edge startstation="s2" endstation="s1"/>'
        return _doc("roadmap", b"<stations>" + stations + b"</stations><edges>" + edges + b"</edges>")
    if choice == 2:  # a complete graph: n^2 edges for the planner
        n = 120
        stations = b"".join(st % (i, i, b"0", b"%d" % (i * 10)) for i in range(n))
        edges = b"".join(b'<edge startstation="s%d" endstation="s%d"/>' % (i, j) for i in range(n) for j in range(n))
        return _doc("roadmap", b"<stations>" + stations + b"</stations><edges>" + edges + b"</edges>")
    if choice == 3:  # absurd numbers
        stations = st % (0, 0, b"-" + MAX_ANGLE, MAX_COORD) + st % (1, 1, MAX_ANGLE, b"0.000001")
        edge = b'<edge startstation="s0" endstation="s1"><points>' + _polygon([(2**31 - 1, -(2**31 - 1))] * 100)
        return _doc("roadmap", b"<stations>" + stations + b"</stations><edges>" + edge + b"</points></edge></edges>")
    # a long edge polyline
    stations = st % (0, 0, b"0", b"0") + st % (1, 1, b"0", b"1")
    edge = b'<edge startstation="s0" endstation="s1">' + _polygon([(i, -i) for i in range(50_000)]) + b"</edge>"
    return _doc("roadmap", b"<stations>" + stations + b"</stations><edges>" + edge + b"</edges>")


def absurd_program(kind: str, rng: random.Random) -> bytes:
    return _absurd_program(rng.randrange(6))


@functools.cache
def _absurd_program(choice: int) -> bytes:
    if choice == 0:  # a tight infinite loop: the interpreter must not spin without yielding
        task = b'<task name="spin"><label name="a"/><goto label="a"/></task>'
    elif choice == 1:  # goto to a label that does not exist
        task = b'<task name="t"><goto label="nowhere" condition="true"/></task>'
    elif choice == 2:  # waits no clock reaches
        task = b'<task name="t"><wait><delay amount="' + MAX_ANGLE + b'"/></wait>'
        task += b'<wait timeout="0" timeoutlabel="x"><random min="1000000" max="0"/></wait></task>'
    elif choice == 3:  # many tasks with the same name and priority
        task = b"".join(
            b'<task name="t" id="1" priority="%d"><log type="i" message="m"/></task>' % i for i in range(500)
        )
    elif choice == 4:  # load of documents that do not exist, parameters set to nonsense
        task = b'<task name="t"><load map="no_such_map" roadmap="nul"/><parameter><set key="IpoTransVel" '
        task += b'value="-' + HUGE_DIGITS[:400] + b'"/></parameter><turnhead angle="' + MAX_ANGLE + b'"/></task>'
    else:  # a long straight program
        task = b'<task name="t">' + b'<log type="info" message="x"/>' * 40_000 + b"</task>"
    return _doc("program", task)


def huge_number(kind: str, rng: random.Random) -> bytes:
    """Numbers no machine number holds where the schema wants a coordinate, an angle or a duration (refused
    since E-XML-025; a target that takes them must not fail later on them)."""
    if kind == "roadmap":
        st = (
            b'<station id="s0" name="S0" angle="-'
            + HUGE_DIGITS
            + b'"><point x="'
            + HUGE_DIGITS
            + b'" y="0"/></station>'
        )
        return _doc("roadmap", b"<stations>" + st + b"</stations><edges/>")
    if kind == "program":
        return _doc("program", b'<task name="t"><wait><delay amount="' + HUGE_DIGITS + b'"/></wait></task>')
    big = b'<point x="' + HUGE_DIGITS + b'" y="-' + HUGE_DIGITS + b'"/>'
    return _doc("map", b'<layer index="0"><line>' + big + big + b"</line></layer>")


Attack = Callable[[str, random.Random], bytes]

ATTACKS: dict[str, Attack] = {
    "billion_laughs": billion_laughs,
    "quadratic_blowup": quadratic_blowup,
    "xxe_file": xxe_file,
    "xxe_network": xxe_network,
    "xxe_parameter": xxe_parameter,
    "external_dtd": external_dtd,
    "xinclude": xinclude,
    "deep_nesting": deep_nesting,
    "huge_attribute": huge_attribute,
    "many_attributes": many_attributes,
    "bad_encoding": bad_encoding,
    "huge_number": huge_number,
}

ABSURD: dict[str, Attack] = {"map": absurd_map, "roadmap": absurd_roadmap, "program": absurd_program}


def attack(kind: str, rng: random.Random) -> tuple[str, bytes]:
    """One hostile document for ``kind``: (attack name, bytes)."""
    r = rng.random()
    if r < 0.35:
        return f"absurd_{kind}", ABSURD[kind](kind, rng)
    if r < 0.355 and kind == "map":
        return "million_points", million_points(kind, rng)
    name = rng.choice(sorted(ATTACKS))
    return name, ATTACKS[name](kind, rng)
