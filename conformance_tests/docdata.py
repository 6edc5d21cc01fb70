"""The documents the suite sends (guide 6.5), valid and invalid, and how it compares documents.

Rules:
- The valid documents live in ``conformance_tests/data/`` (each uses every element of its kind); variants and
  invalid documents are derived from them here, so each invalid one differs from a valid one by one fault.
- Two documents are the same when they parse to the same elements, attributes and text: comments and
  whitespace between elements do not count, the encoding is each document's own (E-XML-011). A server may
  re-serialise a document; it may not change it.
"""

from __future__ import annotations

import functools
from pathlib import Path

from lxml import etree

DATA = Path(__file__).resolve().parent / "data"
FILES = {"map": "map_every_element.map", "roadmap": "roadmap_every_element.rm", "program": "program_every_element.xml"}


@functools.cache
def valid(kind: str) -> bytes:
    return (DATA / FILES[kind]).read_bytes()


def variant(kind: str) -> bytes:
    """Another valid document of ``kind`` (a changed coordinate or log text)."""
    doc = valid(kind)
    if kind == "program":
        return doc.replace(b'message="every element, once"', b'message="every element, variant"')
    return doc.replace(b'<point x="2000" y="0"/>', b'<point x="2100" y="0"/>').replace(
        b'<circle><center x="3000" y="3000"/>', b'<circle><center x="3100" y="3000"/>'
    )


_BILLION_LAUGHS = b"""<?xml version="1.0" encoding="UTF-8"?>
<!DOCTYPE map [
  <!ENTITY lol "lol">
  <!ENTITY lol1 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
  <!ENTITY lol2 "&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;">
  <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
]>
<map Version="1.0"><layer index="0"><hiddenlabel text="&lol3;"><point x="0" y="0"/></hiddenlabel></layer></map>
"""
_XXE = b"""<?xml version="1.0" encoding="UTF-8"?>
<!DOCTYPE map [ <!ENTITY secret SYSTEM "file:///etc/hostname"> ]>
<map Version="1.0"><layer index="0"><hiddenlabel text="x">&secret;<point x="0" y="0"/></hiddenlabel></layer></map>
"""


def invalid(kind: str) -> list[tuple[str, bytes]]:
    """(what is wrong, document) pairs: each must be refused with the active document kept."""
    doc = valid(kind)
    common = [
        ("not well-formed (unclosed root)", doc.rsplit(b"</", 1)[0]),
        ("empty document", b""),
        ("not XML at all", b"this is not a document"),
    ]
    specific: dict[str, list[tuple[str, bytes]]] = {
        "map": [
            (
                "wrong root element <roadmap>",
                b'<?xml version="1.0"?><roadmap Version="1.0"><stations/><edges/></roadmap>',
            ),
            (
                "a <line> with one point",
                doc.replace(
                    b'<line><point x="-5000" y="-5000"/><point x="5000" y="-5000"/>',
                    b'<line><point x="-5000" y="-5000"/>',
                ),
            ),
            ("a coordinate that is not a number", doc.replace(b'<center x="3000"', b'<center x="three"')),
            ("billion laughs (entity declarations)", _BILLION_LAUGHS),
            ("XXE (an external entity)", _XXE),
        ],
        "roadmap": [
            ("wrong root element <map>", b'<?xml version="1.0"?><map Version="1.0"/>'),
            ("an edge to an undefined station", doc.replace(b'endstation="s_c"', b'endstation="nowhere"')),
            ("a coordinate with an exponent", doc.replace(b'<point x="2000" y="0"/>', b'<point x="2e3" y="0"/>')),
        ],
        "program": [
            ("an unknown task command <fly>", doc.replace(b'<label name="start"/>', b'<label name="start"/><fly/>')),
            ('digitalout D3="2"', doc.replace(b'D3="-1"', b'D3="2"', 1)),
            ("wrong root element <map>", b'<?xml version="1.0"?><map Version="1.0"/>'),
        ],
    }
    return common + specific[kind]


def parse(data: bytes | str) -> etree._Element | None:
    """The root element of a document, or None when it is not one (safe parser: no entities, no network)."""
    raw = data.encode("latin-1", "replace") if isinstance(data, str) else data
    parser = etree.XMLParser(
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        remove_comments=True,
        remove_blank_text=True,
        remove_pis=True,
    )
    try:
        root = etree.fromstring(raw, parser)
    except (etree.XMLSyntaxError, ValueError):
        return None
    return root


def _shape(e: etree._Element) -> tuple[object, ...]:
    text = (e.text or "").strip()
    return (e.tag, tuple(sorted(e.attrib.items())), text, tuple(_shape(c) for c in e if isinstance(c.tag, str)))


def same(a: bytes | str, b: bytes | str) -> bool:
    ra, rb = parse(a), parse(b)
    return ra is not None and rb is not None and _shape(ra) == _shape(rb)


def wire_bytes(text: str) -> bytes:
    """A STRING/XML field as the bytes that crossed the wire (the codec maps them 1:1 to Latin-1, E-WIRE-003)."""
    return text.encode("latin-1")


def with_encoding_declared(kind: str) -> bytes:
    """The map in ISO-8859-1, with a non-ASCII label (E-XML-011: the declaration decides)."""
    doc = valid("map").decode("utf-8").replace('encoding="UTF-8"', 'encoding="ISO-8859-1"')
    return doc.replace('text="conformance"', 'text="B\u00fcro \u00e4\u00f6"').encode("latin-1")


def with_doctype(kind: str) -> bytes:
    doc = valid(kind)
    head, rest = doc.split(b"\n", 1)
    return head + b"\n" + f'<!DOCTYPE {kind} SYSTEM "{kind}.dtd">\n'.encode() + rest


def lower_case_version(kind: str) -> bytes:
    return (
        valid(kind)
        .replace(b'<map Version="1.0">', b'<map version="1.0">')
        .replace(b'<roadmap Version="1.0">', b'<roadmap version="1.0">')
    )


def oversize_map(size: int) -> bytes:
    """A valid map of about ``size`` bytes (many lines in one layer)."""
    line = b'<line><point x="0" y="0"/><point x="1000" y="1000"/></line>\n'
    body = line * (size // len(line) + 1)
    head = b'<?xml version="1.0" encoding="UTF-8"?>\n<map Version="1.0"><layer index="0">\n'
    return head + body + b"</layer></map>\n"
