"""Spec coverage of a run: which telegrams, fields, enum values, XSD elements and state-chart cells it exercised.

Rules:
- The denominators come from the spec only (telegrams.yaml, enums.yaml, spec/schemas/*.xsd) and from the
  suite's chart oracle; the numerators from what actually crossed the wire (the sessions report every telegram
  they encode or decode) and what the cases record (transitions observed, documents sent).
- A field is exercised when a telegram carrying it was sent or received; a group's item fields only when the
  group had at least one item. An enum value is exercised when it was sent, or received in a reply.
- Enum values that only a reply can carry and that no protocol command can provoke (the emergency states need
  the hardware stop) are reported apart as "reply-only, not observed": the threshold applies to the metrics a
  client can drive - request and reply telegrams, request enum values, fields of requests, chart cells and XSD
  elements.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Iterable
from dataclasses import dataclass

from lxml import etree

from pltf.conformance_tests import chart
from pltf.spec.codec import REPLIES, REQUESTS
from pltf.spec.documents import SCHEMA_DIR, DocumentKind
from pltf.spec.model import FieldDef, load_enums
from pltf.spec.telegram import Telegram, user_fields

XS = "{http://www.w3.org/2001/XMLSchema}"


def _field_paths(prefix: str, fields: Iterable[FieldDef]) -> list[tuple[str, FieldDef]]:
    out: list[tuple[str, FieldDef]] = []
    for f in user_fields(tuple(fields)):
        path = f"{prefix}.{f.name}"
        out.append((path, f))
        if f.is_group:
            out.extend(_field_paths(path + "[]", f.fields))
    return out


@functools.cache
def all_fields(direction: str) -> dict[str, FieldDef]:
    tset = REQUESTS if direction == "request" else REPLIES
    out: dict[str, FieldDef] = {}
    for cls in tset:
        layout = cls.DEF.layout(direction) if cls.DEF.layout_known else None  # type: ignore[arg-type]
        if layout is None:
            continue
        for path, f in _field_paths(f"{direction}.{cls.NAME}", layout):
            out[path] = f
    return out


@functools.cache
def enum_fields() -> dict[str, set[str]]:
    """Enum name -> the directions ("request", "reply") whose layouts use it."""
    out: dict[str, set[str]] = {}
    for direction in ("request", "reply"):
        for f in all_fields(direction).values():
            if f.enum:
                out.setdefault(f.enum, set()).add(direction)
    return out


@functools.cache
def xsd_elements() -> dict[str, frozenset[str]]:
    """Document kind -> the element names its XSD declares (program includes task)."""
    out: dict[str, frozenset[str]] = {}
    for kind in DocumentKind:
        names: set[str] = set()
        files = [SCHEMA_DIR / f"{kind.value}.xsd"]
        if kind is DocumentKind.PROGRAM:
            files.append(SCHEMA_DIR / "task.xsd")
        for path in files:
            tree = etree.parse(str(path), etree.XMLParser(resolve_entities=False, no_network=True))
            names.update(name for e in tree.iter(f"{XS}element") if (name := e.get("name")))
        out[kind.value] = frozenset(names)
    return out


@dataclass
class Metric:
    name: str
    covered: int
    total: int
    missing: list[str]
    enforced: bool = True

    @property
    def percent(self) -> float:
        return 100.0 if self.total == 0 else 100.0 * self.covered / self.total


class Coverage:
    """Thread-safe recorder (the runner and the cases record from one thread, the stateful tester may not)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.sent_names: set[str] = set()
        self.received_names: set[str] = set()
        self.fields: set[str] = set()
        self.enum_values: dict[str, set[int]] = {}
        self.reply_enum_values: dict[str, set[int]] = {}
        self.elements: dict[str, set[str]] = {}
        self.transitions: set[tuple[str, str, str]] = set()

    # ---- recording
    def sent(self, telegram: Telegram) -> None:
        with self._lock:
            self.sent_names.add(telegram.NAME)
            self._walk("request", telegram)

    def received(self, telegram: Telegram) -> None:
        with self._lock:
            self.received_names.add(telegram.NAME)
            self._walk("reply", telegram)

    def _walk(self, direction: str, telegram: Telegram) -> None:
        layout = telegram.DEF.layout(direction) if telegram.DEF.layout_known else None  # type: ignore[arg-type]
        if layout is None:
            return
        self._fields(direction, f"{direction}.{telegram.NAME}", user_fields(layout), tuple(telegram))

    def _fields(self, direction: str, prefix: str, fields: tuple[FieldDef, ...], values: tuple[object, ...]) -> None:
        for f, v in zip(fields, values, strict=True):
            path = f"{prefix}.{f.name}"
            if f.is_group:
                items = list(v)  # type: ignore[call-overload]
                if items:
                    self.fields.add(path)
                for item in items:
                    self._fields(direction, path + "[]", user_fields(f.fields), tuple(item))
                continue
            self.fields.add(path)
            if f.enum:
                seen = self.enum_values if direction == "request" else self.reply_enum_values
                vals = v if isinstance(v, tuple) else (v,)
                seen.setdefault(f.enum, set()).update(int(x) for x in vals)

    def document(self, kind: str, root: etree._Element) -> None:
        with self._lock:
            self.elements.setdefault(kind, set()).update(e.tag for e in root.iter() if isinstance(e.tag, str))

    def transition(self, source: chart.St, command: str, dest: chart.St) -> None:
        with self._lock:
            self.transitions.add((source.value, command, dest.value))

    # ---- report
    def metrics(self) -> list[Metric]:
        req_names = [c.NAME for c in REQUESTS]
        rep_names = [c.NAME for c in REPLIES if c.DEF.answered]
        enums = load_enums()
        req_enum = [
            (e, n, v) for e, dirs in enum_fields().items() if "request" in dirs for n, v in enums[e].values.items()
        ]
        rep_only = [
            (e, n, v) for e, dirs in enum_fields().items() if dirs == {"reply"} for n, v in enums[e].values.items()
        ]
        seen = {e: self.enum_values.get(e, set()) | self.reply_enum_values.get(e, set()) for e in enums}
        cells = [(s.value, c, d.value) for s, c, d in chart.every_transition()]
        els = [(k, n) for k, names in xsd_elements().items() if k != "task" for n in sorted(names)]
        req_fields = sorted(all_fields("request"))
        rep_fields = sorted(all_fields("reply"))

        def metric(name: str, items: list[str], covered: set[str], enforced: bool = True) -> Metric:
            missing = [i for i in items if i not in covered]
            return Metric(name, len(items) - len(missing), len(items), missing, enforced)

        return [
            metric("request telegrams sent", req_names, self.sent_names),
            metric("reply telegrams received", rep_names, self.received_names),
            metric("request fields", req_fields, self.fields),
            metric("reply fields", rep_fields, self.fields, enforced=False),
            metric(
                "request enum values",
                [f"{e}.{n}" for e, n, _ in req_enum],
                {f"{e}.{n}" for e, n, v in req_enum if v in seen[e]},
            ),
            metric(
                "reply-only enum values observed",
                [f"{e}.{n}" for e, n, _ in rep_only],
                {f"{e}.{n}" for e, n, v in rep_only if v in seen[e]},
                enforced=False,
            ),
            metric(
                "XSD elements sent",
                [f"{k}:{n}" for k, n in els],
                {f"{k}:{n}" for k, n in els if n in self.elements.get(k, set())},
            ),
            metric(
                "state-chart cells",
                [f"{s} --{c}--> {d}" for s, c, d in cells],
                {f"{s} --{c}--> {d}" for s, c, d in self.transitions},
            ),
        ]

    def below(self, threshold: float) -> list[Metric]:
        return [m for m in self.metrics() if m.enforced and m.percent < threshold]

    def as_dict(self) -> dict[str, object]:
        return {
            m.name: {
                "covered": m.covered,
                "total": m.total,
                "percent": round(m.percent, 1),
                "enforced": m.enforced,
                "missing": m.missing,
            }
            for m in self.metrics()
        }
