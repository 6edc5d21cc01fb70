"""Guide 6.3 platform data commands and 6.5 XML documents: map, roadmap and program - set, get, save, load.

Rules of this module: every case first GETs the active document and restores it at the end; the cases that
SAVE first LOAD the stored document and SAVE it back, so the stored file ends with the content it had.
"""

from __future__ import annotations

from functools import partial

from pltf.conformance_tests import docdata
from pltf.conformance_tests.cases._common import STATES, no_unsolicited
from pltf.conformance_tests.catalogue import Level, Tier, add, case
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Fail
from pltf.conformance_tests.target import Status
from pltf.spec.codec import build
from pltf.spec.telegram import Telegram

KINDS = ("map", "roadmap", "program")
_NAME = "conformance"


def _set(ctx: CaseContext, kind: str, xml: bytes, name: str = _NAME) -> None:
    ctx.session().send(_setter(ctx, kind, xml, name))


def _setter(ctx: CaseContext, kind: str, xml: bytes, name: str = _NAME) -> Telegram:
    """The CMD_SET_<kind> telegram of ``xml`` (its elements are counted as covered)."""
    text = xml.decode("latin-1")
    root = docdata.parse(xml)
    if root is not None and root.tag == kind:
        ctx.target.coverage.document(kind, root)
    if kind == "program":
        return build("request", "CMD_SET_PROGRAM", xml=text)
    return build("request", f"CMD_SET_{kind.upper()}", name=name, xml=text)


def _get(ctx: CaseContext, kind: str) -> tuple[str, str]:
    reply = ctx.get(f"CMD_GET_{kind.upper()}")
    return reply.xml, getattr(reply, "name", "")  # type: ignore[attr-defined]


def _expect_active(ctx: CaseContext, kind: str, expected: bytes, how: str, name: str | None = None) -> None:
    _judge_active(ctx, kind, ctx.get(f"CMD_GET_{kind.upper()}"), expected, how, name)


def _judge_active(ctx: CaseContext, kind: str, reply: Telegram, expected: bytes, how: str, name: str | None) -> None:
    """``reply`` (to CMD_GET_<kind>) carries the ``expected`` document (and ``name``)."""
    xml, got_name = reply.xml, getattr(reply, "name", "")  # type: ignore[attr-defined]
    if docdata.same(xml, expected):
        if name is not None and kind != "program" and got_name != name:
            raise Fail(f"{how}: CMD_GET_{kind.upper()} returns the document but the name {got_name!r}, not {name!r}")
        return
    if kind != "program" and docdata.same(got_name, expected):
        ctx.deviate("E-REP-013", 1, f"CMD_GET_{kind.upper()} sends the name first, then the XML")
        return
    if kind == "program" and xml and docdata.parse(xml) is None:
        ctx.deviate("E-REP-014", 0, f"CMD_GET_PROGRAM returned {xml[:40]!r}, not the program document")
        return
    raise Fail(
        f"{how}: CMD_GET_{kind.upper()} returns {len(xml)} bytes that are not the expected document ({xml[:60]!r}...)"
    )


def _round_trip(ctx: CaseContext, kind: str) -> None:
    ctx.ready()
    ctx.preserve_document(kind)
    for doc in (docdata.valid(kind), docdata.variant(kind)):
        _set(ctx, kind, doc)
        _expect_active(ctx, kind, doc, f"CMD_SET_{kind.upper()}", name=_NAME)
    xml, _ = _get(ctx, kind)
    if docdata.wire_bytes(xml) != docdata.variant(kind):
        ctx.note("the document came back re-serialised (same content, other bytes)")


def _invalid(ctx: CaseContext, kind: str) -> None:
    ctx.ready()
    ctx.preserve_document(kind)
    good = docdata.valid(kind)
    _set(ctx, kind, good)
    _expect_active(ctx, kind, good, "a valid document")
    for what, bad in docdata.invalid(kind):
        _set(ctx, kind, bad, name="conformance_invalid")
        try:
            _expect_active(ctx, kind, good, f"after an invalid {kind} ({what})", name=_NAME)
        except Fail as exc:
            raise Fail(
                f"an invalid {kind} ({what}) was not refused, or the active one was lost: {exc}",
                erratum="E-XML-012" if "entit" in what.lower() else None,
            ) from None


def _save_load(ctx: CaseContext, kind: str) -> None:
    ctx.ready()
    ctx.preserve_document(kind)
    up = kind.upper()
    ctx.send(f"CMD_LOAD_{up}")
    stored, stored_name = _get(ctx, kind)
    doc, other = docdata.valid(kind), docdata.variant(kind)
    _set(ctx, kind, doc)
    ctx.send(f"CMD_SAVE_{up}")
    _set(ctx, kind, other)
    _expect_active(ctx, kind, other, f"CMD_SET_{up} after CMD_SAVE_{up}")
    ctx.send(f"CMD_LOAD_{up}")
    try:
        _expect_active(ctx, kind, doc, f"CMD_SAVE_{up} then CMD_LOAD_{up}")
    finally:
        if stored.strip():
            _set(ctx, kind, docdata.wire_bytes(stored), name=stored_name)
            ctx.send(f"CMD_SAVE_{up}")
        else:
            ctx.note(f"no {kind} was stored before; the suite's document stays stored")


def _every_state(ctx: CaseContext, kind: str, command: str) -> None:
    ctx.ready()
    ctx.preserve_document(kind)
    up = kind.upper()
    if command != f"CMD_SET_{up}":
        ctx.send(f"CMD_LOAD_{up}")
    active, name = _get(ctx, kind)
    for state in STATES:
        if command == f"CMD_SET_{up}":
            sent = _setter(ctx, kind, docdata.wire_bytes(active) if active.strip() else docdata.valid(kind), name=name)
        else:
            sent = build("request", command)
        then = [sent]
        if active.strip():  # then the document must still be the active one
            then.append(build("request", f"CMD_GET_{up}"))
        before, rest = ctx.enter(state, then=[*then, build("request", "CMD_GET_STATUS")])  # pipelined (E-WIRE-008)
        replies = rest()
        after = Status.of(replies[-1])
        if (after.op, after.mode) != (before.op, before.mode):
            raise Fail(f"{command} in {state.value} changed the platform: {before.describe()} -> {after.describe()}")
        if active.strip():
            _judge_active(ctx, kind, replies[0], docdata.wire_bytes(active), f"{command} in {state.value}", None)
    no_unsolicited(ctx, command)
    ctx.ready()


for _kind in KINDS:
    _up = _kind.upper()
    add(
        f"6.3/CMD_SET_{_up}/round-trip",
        partial(_round_trip, kind=_kind),
        group="documents",
        tier=Tier.SMOKE if _kind == "map" else Tier.STANDARD,
        errata=("E-REP-013",) if _kind != "program" else ("E-REP-014",),
        level=Level.MUST,
        requirement=f'guide 6.3 CMD_SET_{_up}: "Set ... The {_kind} is specified in an XML-document"; '
        f'CMD_GET_{_up}: "Request ... to send" it - a valid document using every element of 6.5 '
        "becomes active and is returned with the same content",
        telegrams=(f"CMD_SET_{_up}", f"CMD_GET_{_up}"),
    )
    add(
        f"6.3/CMD_SET_{_up}/invalid-refused",
        partial(_invalid, kind=_kind),
        group="documents",
        errata=("E-XML-012",),
        requirement=f"issue and errata E-XML-012/E-XML-021: a {_kind} that is not well-formed, unsafe (entity "
        "declarations) or invalid against the schema of guide 6.5 is refused and the active one is "
        "kept",
        telegrams=(f"CMD_SET_{_up}", f"CMD_GET_{_up}"),
    )
    add(
        f"6.3/CMD_SAVE_{_up}/load-round-trip",
        partial(_save_load, kind=_kind),
        group="documents",
        errata=("E-CMD-008",),
        requirement=f'guide 6.3 CMD_SAVE_{_up}: "Save ... on the hard disk of the platform", CMD_LOAD_{_up}: '
        '"Load ... from the hard disk" - LOAD after SAVE brings back the saved document',
        telegrams=(f"CMD_SAVE_{_up}", f"CMD_LOAD_{_up}"),
    )
    for _cmd in (f"CMD_SET_{_up}", f"CMD_LOAD_{_up}", f"CMD_SAVE_{_up}"):
        add(
            f"6.3/{_cmd}/every-state",
            partial(_every_state, kind=_kind, command=_cmd),
            group="documents",
            requirement=f"guide 4.2: commands cause state transitions only as the state chart says - {_cmd} "
            "(a platform data command) changes no operation state, is not answered, and keeps "
            "the document in every state",
            telegrams=(_cmd,),
        )


@case(
    "6.5/xml/lower-case-version",
    group="documents",
    errata=("E-XML-001",),
    requirement="erratum E-XML-001: <map> and <roadmap> take Version or version",
    telegrams=("CMD_SET_MAP", "CMD_SET_ROADMAP"),
)
def lower_case_version(ctx: CaseContext) -> None:
    ctx.ready()
    for kind in ("map", "roadmap"):
        ctx.preserve_document(kind)
        doc = docdata.lower_case_version(kind)
        _set(ctx, kind, doc)
        xml, _ = _get(ctx, kind)
        if not docdata.same(xml, doc):
            ctx.deviate("E-XML-001", 0, f"a {kind} with version= (lower case) was refused")


@case(
    "6.5/xml/declared-encoding",
    group="documents",
    errata=("E-XML-011",),
    requirement="erratum E-XML-011: a document is decoded as its XML declaration says - an ISO-8859-1 map with "
    "umlauts is accepted and returned with the same text",
    telegrams=("CMD_SET_MAP",),
)
def declared_encoding(ctx: CaseContext) -> None:
    ctx.ready()
    ctx.preserve_document("map")
    doc = docdata.with_encoding_declared("map")
    _set(ctx, "map", doc)
    _expect_active(ctx, "map", doc, "an ISO-8859-1 map")


@case(
    "6.5/xml/doctype-without-entities",
    group="documents",
    errata=("E-XML-012",),
    requirement='erratum E-XML-012: a DOCTYPE without an internal subset (<!DOCTYPE map SYSTEM "map.dtd">) is '
    "allowed and ignored, the external DTD never fetched",
    telegrams=("CMD_SET_MAP",),
)
def doctype(ctx: CaseContext) -> None:
    ctx.ready()
    ctx.preserve_document("map")
    doc = docdata.with_doctype("map")
    _set(ctx, "map", doc)
    xml, _ = _get(ctx, "map")
    if not docdata.same(xml, doc):
        ctx.deviate("E-XML-012", 0, "a map with a DOCTYPE (no internal subset) was refused")


@case(
    "6.5/xml/oversize-refused",
    group="documents",
    tier=Tier.EXHAUSTIVE,
    errata=("E-XML-021",),
    requirement="erratum E-XML-021: documents over 8 MiB are refused as invalid; the active one stays",
    telegrams=("CMD_SET_MAP",),
)
def oversize(ctx: CaseContext) -> None:
    ctx.ready()
    ctx.preserve_document("map")
    good = docdata.valid("map")
    _set(ctx, "map", good)
    _set(ctx, "map", docdata.oversize_map(9 * 1024 * 1024))
    xml, _ = _get(ctx, "map")
    if not docdata.same(xml, good):
        ctx.deviate("E-XML-021", 0, "a 9 MiB map was accepted")


@case(
    "6.2/framing/large-document",
    group="documents",
    tier=Tier.EXHAUSTIVE,
    level=Level.SHOULD,
    errata=("E-WIRE-004",),
    requirement="erratum E-WIRE-004 / E-XML-021: a 4 MiB map (well under both limits) crosses the wire and is accepted",
    telegrams=("CMD_SET_MAP",),
)
def large_document(ctx: CaseContext) -> None:
    ctx.ready()
    ctx.preserve_document("map")
    doc = docdata.oversize_map(4 * 1024 * 1024)
    s = ctx.session()
    s.send(build("request", "CMD_SET_MAP", name=_NAME, xml=doc.decode("latin-1")))
    xml, _ = _get(ctx, "map")
    if len(xml) != len(doc) and not docdata.same(xml, doc):
        raise Fail(f"a 4 MiB map was not accepted (GET returns {len(xml)} bytes)")
