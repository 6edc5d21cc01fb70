"""Go client: module ``platformctrl`` (standard library only), typed structs and int32 enum types."""

from __future__ import annotations

import functools

from pltf.stubgen import banner, fill, model, readme, template
from pltf.stubgen.model import ERRORS, Field, Message, doc_line, pascal, words
from pltf.stubgen.renderer import Spelling, arguments, convert, methods, protocol, scripts, static

KEYWORDS = frozenset(
    (
        "break",
        "case",
        "chan",
        "const",
        "continue",
        "default",
        "defer",
        "else",
        "fallthrough",
        "for",
        "func",
        "go",
        "goto",
        "if",
        "import",
        "interface",
        "map",
        "package",
        "range",
        "return",
        "select",
        "struct",
        "switch",
        "type",
        "var",
    )
)
INITIALISMS = {"id": "ID", "xml": "XML", "ip": "IP", "tcp": "TCP", "gps": "GPS", "io": "IO"}
GO_TYPE = {
    "BYTE": "uint8",
    "BOOL": "bool",
    "INT16": "int16",
    "INT": "int32",
    "DOUBLE": "float64",
    "STRING": "string",
    "XML": "string",
}
# Names the runtime declares: an enum constant that would clash is prefixed with its type's name.
RUNTIME_NAMES = frozenset(
    (
        "DefaultMaxLength",
        "FieldType",
        "Field",
        "Layout",
        "Direction",
        "Request",
        "Reply",
        "Telegram",
        "ProtocolError",
        "FrameData",
        "EncodeData",
        "Encode",
        "DecodeData",
        "Decoder",
        "NewDecoder",
        "DecodeFrame",
        "Dump",
        "Client",
        "Dial",
    )
)
HEAD = banner("// ")
# Values cross the runtime as any: int64, float64, string, []byte, []any (arrays, group items).
TO_VALUE = {
    "group": "groupToValues({x})",
    "array": "intsToValues({x}[:])",
    "BOOL": "b2i({x})",
    "DOUBLE": "{x}",
    "text": "{x}",
    "int": "int64({x})",
}
FROM_VALUE = {
    "group": "{x} = valuesToGroup[{item}]({v})",
    "array": "valuesToInts({v}, {x}[:])",
    "BOOL": "{x} = {v}.(int64) != 0",
    "DOUBLE": "{x} = {v}.(float64)",
    "text": "{x} = {v}.(string)",
    "int": "{x} = {base}({v}.(int64))",
}
METHOD = (
    "// {name} sends {m.name} (id {m.id}): {summary}\nfunc (c *Client) {name}({params}) error {{\n"
    "\treturn c.Send({req})\n}}\n",
    "// {name} sends {m.name} (id {m.id}): {summary}\nfunc (c *Client) {name}({params}) (*{reply}, error) {{\n"
    "\tt, err := c.Request({req}, {m.id})\n\tif err != nil {{\n\t\treturn nil, err\n\t}}\n"
    "\treturn t.(*{reply}), nil\n}}\n",
)


def go_name(name: str) -> str:
    return "".join(INITIALISMS.get(w.lower(), w[:1].upper() + w[1:].lower()) for w in words(name))


SPELLING = Spelling(
    scalars=GO_TYPE,
    group="[]{item}",
    array="[{repeat}]{base}",
    head='Name: "{f.name}", Type: {type}',
    type_name=lambda t: "Field" + go_name(t),
    wrap=("{", "}"),
    attrs={
        "repeat": "Repeat: {f.repeat}",
        "const": "HasConst: true, Const: {f.const}",
        "min": "HasMin: true, Min: {f.min}",
        "max": "HasMax: true, Max: {f.max}",
        "allowed": "Allowed: []int64{{{allowed}}}",
        "group": "Fields: fields{item}, ItemMin: {f.item_min}",
        "run": "Run: {f.run}",
    },
    empty="nil",
    open="[]Field{",
    close="}}",
    step="\t",
    # Doc comments above each field: gofmt then aligns nothing, so the output is gofmt-clean as written.
    member="\t// {doc}\n\t{name} {type}",
    field_name=go_name,
)


def param(name: str) -> str:
    p = go_name(name)
    p = p[:1].lower() + p[1:] if not p.isupper() else p.lower()
    return p + "_" if p in KEYWORDS else p


@functools.cache
def _enum_consts() -> dict[tuple[str, str], str]:
    plain: dict[str, list[str]] = {}
    for name, e in model.enums().items():
        for value in e.values:
            plain.setdefault(pascal(value), []).append(name)
    taken = RUNTIME_NAMES | set(model.item_types()) | set(model.enums())
    out = {}
    for name, e in model.enums().items():
        for value in e.values:
            p = pascal(value)
            out[(name, value)] = name + p if len(plain[p]) > 1 or p in taken else p
    return out


def _errors() -> str:
    lines = ["var errorParents = map[string]string{"]
    lines += [f'\t// {doc}\n\t"{name}": "{parent or ""}",' for name, parent, doc in ERRORS]
    lines.append("}\n\n// The error family: match with errors.Is(err, ErrTruncated).\nvar (")
    for name, _, _ in ERRORS:
        lines.append(f"\t// Err{name} matches every {name}.")
        lines.append(f'\tErr{name} = &ProtocolError{{Kind: "{name}"}}')
    return "\n".join(lines) + "\n)"


def _conversions(recv: str, fields: tuple[Field, ...]) -> tuple[str, str]:
    user = [f for f in fields if f.user]
    values = ", ".join(convert(TO_VALUE, f, x=f"{recv}.{go_name(f.name)}") for f in user)
    sets = "".join(
        f"\t{convert(FROM_VALUE, f, x=f'{recv}.{go_name(f.name)}', v=f'v[{i}]', base=SPELLING.type(f))}\n"
        for i, f in enumerate(user)
    )
    return values, sets


def _func(signature: str, body: str) -> str:
    # Always multi-line: gofmt aligns consecutive one-line functions and breaks long ones.
    return f"func {signature} {{\n{body}}}\n" if body else f"func {signature} {{}}\n"


def _telegram(m: Message) -> str:
    t = m.type_name
    out = [f"// {t} is {m.doc}"]
    if m.opaque:
        out += [
            f"type {t} struct {{\n\t// Payload is the bytes after the identifier (layout unknown).\n"
            f"\tPayload []byte\n}}\n",
            f"var layout{t} = Layout{{Opaque: true}}\n",
            _func(f"(t *{t}) Values() []any", "\treturn []any{t.Payload}\n"),
            _func(f"(t *{t}) setValues(v []any)", "\tt.Payload = v[0].([]byte)\n"),
        ]
    else:
        body = SPELLING.members(m.fields)
        out.append(f"type {t} struct {{\n" + "\n".join(body) + "\n}\n" if body else f"type {t} struct{{}}\n")
        out.append(f"var layout{t} = Layout{{Fields: {SPELLING.table(m.fields)}}}\n")
        values, sets = _conversions("t", m.fields)
        out.append(_func(f"(t *{t}) Values() []any", f"\treturn []any{{{values}}}\n"))
        out.append(_func(f"(t *{t}) setValues(v []any)", sets))
    direction = "Request" if m.direction == "request" else "Reply"
    out += [
        _func(f"(*{t}) TelegramID() uint8", f"\treturn {m.id}\n"),
        _func(f"(*{t}) TelegramName() string", f'\treturn "{m.name}"\n'),
        _func(f"(*{t}) TelegramDirection() Direction", f"\treturn {direction}\n"),
        _func(f"(*{t}) TelegramLayout() *Layout", f"\treturn &layout{t}\n"),
    ]
    return "\n".join(out)


def _enum(name: str) -> str:
    consts = _enum_consts()
    values = [
        f"\t// {consts[(name, k)]} is {k}.\n\t{consts[(name, k)]} {name} = {v}"
        for k, v in model.enums()[name].values.items()
    ]
    return "\n".join(
        [
            f"// {name}: {model.enum_doc(name)}\ntype {name} int32\n",
            f"// The values of {name}.\nconst (",
            *values,
            ")\n",
        ]
    )


def _item(name: str, fields: tuple[Field, ...]) -> str:
    values, sets = _conversions("p", fields)
    return "\n".join(
        [
            f"// {name} is one item of a repeated group.\ntype {name} struct {{",
            *SPELLING.members(fields),
            "}\n",
            f"var fields{name} = {SPELLING.table(fields)}\n",
            _func(f"(p *{name}) values() []any", f"\treturn []any{{{values}}}\n"),
            _func(f"(p *{name}) setValues(v []any)", sets),
        ]
    )


def _registry(direction: str, telegrams: tuple[Message, ...]) -> str:
    cases = [f"\tcase {m.id}:\n\t\treturn &{m.type_name}{{}}" for m in telegrams]
    func = "newRequest" if direction == "request" else "newReply"
    return "\n".join([f"func {func}(id uint8) Telegram {{\n\tswitch id {{", *cases, "\t}\n\treturn nil\n}\n"])


def _protocol() -> str:
    head = [
        HEAD,
        "// Enums, group items and telegram types of the PlatformCtrl protocol (guide 6.3, 6.4).\n",
        "package platformctrl\n",
    ]
    return protocol(head, _enum, _item, _telegram, _registry)


def method_name(m: Message) -> str:
    return go_name(m.base)


def _method(m: Message) -> dict[str, str]:
    params, inits = arguments(
        m,
        ("payload []byte", "Payload: payload"),
        lambda f: (f"{param(f.name)} {SPELLING.type(f)}", f"{go_name(f.name)}: {param(f.name)}"),
    )
    return {
        "name": method_name(m),
        "params": ", ".join(params),
        "req": f"&{m.type_name}{{{', '.join(inits)}}}",
        "summary": doc_line(m.summary),
    }


README = readme("go", "Go", "`go build ./cmd/...`, Go 1.19+")


def render() -> dict[str, str]:
    return {
        "README.md": README,
        "go.mod": HEAD + "module platformctrl\n\ngo 1.19\n",
        "wire.go": HEAD + fill(template("go", "wire.go.tmpl"), ERRORS=_errors()),
        "protocol.go": _protocol(),
        "client.go": HEAD + fill(template("go", "client.go.tmpl"), METHODS=methods(_method, METHOD, lead="")),
        **static("go", HEAD, {"cmd/smoke/main.go": "smoke.go.tmpl", "cmd/vectors/main.go": "vectors.go.tmpl"}),
        **scripts(
            "go",
            "build the package and the programs into build/ (Go 1.19+, no dependencies).",
            "./build/smoke",
            "./build/vectors",
            "build/\n",
        ),
    }
