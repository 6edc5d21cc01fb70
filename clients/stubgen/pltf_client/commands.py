"""``_commands.py``: one method per command, for the sync (``Commands``) and asyncio (``AsyncCommands``) clients.

Rules:
- A command's arguments are its request's user fields, named with their unit; an answered request (GET_*) also
  takes ``timeout`` and returns its typed reply, a command returns None (guide 6.1: never acknowledged).
- The classes' heads and the module's helpers are ``templates/pltf_client/_commands.py.tmpl``; this module
  renders the methods between its placeholders.
"""

from __future__ import annotations

from pltf.stubgen import fill, template
from pltf.stubgen.model import Command, Field, commands
from pltf.stubgen.pltf_client.layout import docstring, field_doc, fits, imports
from pltf.stubgen.pltf_client.names import (
    check_unique,
    is_bool,
    item_name,
    method_name,
    py_name,
    reply_class_name,
    scalar_type,
)

IND = "    "
OPAQUE_DOC = "The telegram's data after the identifier, sent verbatim (no layout is known)."
XML_DOC = " A str is sent UTF-8 encoded (the XML default); bytes are sent as they are."
TIMEOUT_DOC = "Seconds to wait for the reply; None uses the client's default timeout."
RAISES = [("Timeout", "no reply in time."), ("ConnectionClosed", "the connection is gone.")]


def arg_type(f: Field) -> str:
    if f.is_group:
        inner = ", ".join(scalar_type(g, "request") for g in f.user_fields)
        return f"Sequence[{item_name(f)} | tuple[{inner}]]"
    scalar = scalar_type(f, "request")
    if f.repeat:
        return "bytes | Sequence[int]" if f.type == "BYTE" and scalar == "int" else f"Sequence[{scalar}]"
    return scalar


def arg_expr(f: Field, var: str) -> str:
    if f.is_group:
        return f"tuple(tuple(_it) for _it in {var})"
    if f.repeat:
        return f"tuple({var})"
    if f.enum is not None and not is_bool(f):
        return f"int({var})"
    if f.type == "XML":
        return f"_xml_arg({var})"
    return var


def arg_doc(f: Field) -> str:
    doc = field_doc(f)
    if f.is_group:
        item = item_name(f)
        doc = f"{f.description.rstrip('.')}: {item} items ({', '.join(py_name(g, item) for g in f.fields)})."
    return doc + XML_DOC if f.type == "XML" else doc


def _arguments(command: Command) -> tuple[list[str], list[tuple[str, str]], list[str]]:
    """The method's parameters, their docs and the request's keyword arguments."""
    m = command.request
    if m.opaque:
        return ['payload: bytes = b""'], [("payload", OPAQUE_DOC)], ["payload=bytes(payload)"]
    check_unique([py_name(f) for f in m.user_fields], m.name)
    params = [f"{py_name(f)}: {arg_type(f)}" for f in m.user_fields]
    docs = [(py_name(f), arg_doc(f)) for f in m.user_fields]
    return params, docs, [f"{f.name}={arg_expr(f, py_name(f))}" for f in m.user_fields]


def method(command: Command, is_async: bool) -> list[str]:
    m, answered = command.request, command.reply is not None
    params, args_doc, build_args = _arguments(command)
    params = ["self", *params]
    reply_cls = reply_class_name(m.name) if answered else None
    if answered:
        params += ["*", "timeout: float | None = None"]
        args_doc.append(("timeout", TIMEOUT_DOC))
    head = f"{IND}{'async ' if is_async else ''}def {method_name(m.name)}("
    sig = f"{head}{', '.join(params)}) -> {reply_cls or 'None'}:"
    lines = [sig] if fits(sig) else [head, *[f"{IND}    {p}," for p in params], f"{IND}) -> {reply_cls or 'None'}:"]
    paras = [m.summary]
    if answered:
        paras.append(f"Sends {m.name} (id {m.id}; guide {m.section}) and waits for its reply.")
    else:
        paras.append(
            f"Sends {m.name} (id {m.id}; guide {m.section}). The platform does not acknowledge commands "
            "(guide 6.1): see the effect in get_status() or with a wait_* method."
        )
    sections = [("Args", args_doc)]
    if answered:
        sections += [("Returns", [(reply_cls or "", "the typed reply.")]), ("Raises", RAISES)]
    lines += docstring(IND * 2, paras, sections)
    call = f'_request("{m.name}"{"".join(", " + a for a in build_args)})'
    aw = "await " if is_async else ""

    def send(telegram: str) -> str:
        if answered:
            return f"{IND * 2}return {reply_cls}.from_telegram({aw}self.request({telegram}, timeout))"
        return f"{IND * 2}{aw}self.send({telegram})"

    return [*lines, send(call)] if fits(send(call)) else [*lines, f"{IND * 2}telegram = {call}", send("telegram")]


def render_commands(banner: str) -> str:
    every = commands()
    enums_used = {
        f.enum
        for c in every
        if not c.request.opaque
        for f in c.request.user_fields
        if f.enum is not None and not is_bool(f)
    }
    request_items = {item_name(f) for c in every if not c.request.opaque for f in c.request.fields if f.is_group}
    replies = [reply_class_name(c.request.name) for c in every if c.reply is not None]
    check_unique([method_name(c.request.name) for c in every], "method names")
    sync = [line for c in every for line in ("", *method(c, False))]
    aio = [line for c in every for line in ("", *method(c, True))]
    return fill(
        template("pltf_client", "_commands.py.tmpl"),
        BANNER=banner,
        IMPORTS="\n".join(
            [*imports("pltf.client._enums", enums_used), *imports("pltf.client._replies", [*replies, *request_items])]
        ),
        METHODS="\n".join(sync),
        ASYNC_METHODS="\n".join(aio),
    )
