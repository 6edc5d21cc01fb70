"""The one place that parses and validates PlatformCtrl XML documents (guide 6.5).

Rules:
- bytes in, a validated ``lxml`` tree out, or ``DocumentError`` (a ``ValueError``) with one line naming the
  problem and its line number; never any other exception for any input bytes.
- parsing is safe: no entity substitution, no network, no DTD loading, no huge trees; a DOCTYPE that
  declares entities is refused (billion laughs, XXE); a DOCTYPE without them is allowed and ignored
  (an external DTD is never fetched). Documents over ``max_size`` bytes or nested deeper than
  ``MAX_DEPTH`` elements are refused before validation (spec/errata/xml.yaml E-XML-012, E-XML-021).
- the encoding is the XML declaration's, UTF-8 when there is none (E-XML-011).
- the XSDs in spec/schemas are compiled once per process; no other I/O.
"""

from __future__ import annotations

import enum
import functools
import threading
from pathlib import Path

from lxml import etree

__all__ = [
    "DEFAULT_MAX_SIZE",
    "MAX_DEPTH",
    "SCHEMA_DIR",
    "DocumentError",
    "DocumentKind",
    "detect_kind",
    "schema_path",
    "validate_document",
]

DEFAULT_MAX_SIZE = 8 * 1024 * 1024
MAX_DEPTH = 64
SCHEMA_DIR = Path(__file__).parent / "schemas"
_VALIDATE_LOCK = threading.Lock()  # an XMLSchema keeps its error_log on itself


class DocumentKind(enum.StrEnum):
    """The four documents of guide 6.5; the value is the root element's name and the schema's stem."""

    MAP = "map"
    ROADMAP = "roadmap"
    PROGRAM = "program"
    TASK = "task"


class DocumentError(ValueError):
    """A document that is not well-formed, unsafe, too big, or invalid against its schema."""

    def __init__(self, reason: str, *, kind: DocumentKind | None = None, line: int | None = None) -> None:
        self.reason = " ".join(reason.split())
        self.kind = kind
        self.line = line
        where = f"{kind} document" if kind is not None else "document"
        if line is not None:
            where += f", line {line}"
        super().__init__(f"{where}: {self.reason}")


def schema_path(kind: DocumentKind) -> Path:
    """The XSD shipped for ``kind`` (program.xsd includes task.xsd)."""
    return SCHEMA_DIR / f"{kind.value}.xsd"


def _safe_parser() -> etree.XMLParser:
    return etree.XMLParser(
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        dtd_validation=False,
        attribute_defaults=False,
        huge_tree=False,
    )


@functools.cache
def _schema(kind: DocumentKind) -> etree.XMLSchema:
    return etree.XMLSchema(etree.parse(str(schema_path(kind)), _safe_parser()))


# True when some element sits deeper than MAX_DEPTH: one XPath step per level, in libxml2, instead of a Python walk
# over every element (the walk below runs only to name the depth of a document already refused).
_TOO_DEEP = etree.XPath("boolean(/*" + "/*" * MAX_DEPTH + ")")


def _depth(root: etree._Element) -> int:
    deepest, depth = 0, 0
    for event, _ in etree.iterwalk(root, events=("start", "end")):
        depth += 1 if event == "start" else -1
        deepest = max(deepest, depth)
    return deepest


def _parse(data: bytes, kind: DocumentKind | None, max_size: int) -> etree._ElementTree:
    if not isinstance(data, bytes | bytearray | memoryview):
        raise DocumentError(f"expected bytes, got {type(data).__name__}", kind=kind)
    data = bytes(data)
    if len(data) > max_size:
        raise DocumentError(f"document is {len(data)} bytes, over the limit of {max_size}", kind=kind)
    # Refuse before libxml2 sees the DTD at all (ASCII-compatible encodings) ...
    if b"<!ENTITY" in data:
        raise DocumentError("entity declarations are not allowed", kind=kind)
    try:
        root = etree.fromstring(data, _safe_parser())
    except etree.XMLSyntaxError as exc:
        raise DocumentError(f"not well-formed XML: {exc.msg}", kind=kind, line=exc.lineno) from None
    except ValueError as exc:  # e.g. an unsupported encoding name
        raise DocumentError(f"not well-formed XML: {exc}", kind=kind) from None
    if root is None:
        raise DocumentError("empty document", kind=kind)
    tree = root.getroottree()
    # ... and after it, for any encoding (e.g. UTF-16) the byte scan cannot see.
    dtd = tree.docinfo.internalDTD
    if dtd is not None and any(True for _ in dtd.iterentities()):
        raise DocumentError("entity declarations are not allowed", kind=kind)
    if _TOO_DEEP(root):
        deepest = _depth(root)
        raise DocumentError(f"elements nested {deepest} deep, over the limit of {MAX_DEPTH}", kind=kind)
    return tree


def _kind_of(root: etree._Element) -> DocumentKind | None:
    tag = root.tag
    if isinstance(tag, str):
        for kind in DocumentKind:
            if tag == kind.value:
                return kind
    return None


def detect_kind(data: bytes, *, max_size: int = DEFAULT_MAX_SIZE) -> DocumentKind:
    """The kind of document ``data`` is, from its root element's name (not validated)."""
    root = _parse(data, None, max_size).getroot()
    kind = _kind_of(root)
    if kind is None:
        expected = ", ".join(f"<{k.value}>" for k in DocumentKind)
        raise DocumentError(f"unknown root element <{root.tag!s}>, expected one of {expected}", line=root.sourceline)
    return kind


def validate_document(kind: DocumentKind, data: bytes, *, max_size: int = DEFAULT_MAX_SIZE) -> etree._ElementTree:
    """Parse ``data`` safely and validate it as a ``kind`` document; return the tree or raise DocumentError."""
    kind = DocumentKind(kind)
    tree = _parse(data, kind, max_size)
    root = tree.getroot()
    if _kind_of(root) is not kind:
        raise DocumentError(f"root element is <{root.tag!s}>, expected <{kind.value}>", kind=kind, line=root.sourceline)
    schema = _schema(kind)
    with _VALIDATE_LOCK:
        valid = schema.validate(tree)
        error = None if valid else schema.error_log[0]
    if error is not None:
        raise DocumentError(error.message, kind=kind, line=error.line)
    return tree
