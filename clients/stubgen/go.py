"""Go client: module ``platformctrl`` (standard library only), typed structs and int32 enum types."""

from __future__ import annotations

from clients.stubgen import banner, fill, readme, template
from clients.stubgen.model import (
    ERRORS,
    Field,
    Message,
    commands,
    doc_line,
    enums,
    field_doc,
    item_types,
    messages,
    pascal,
    words,
)

KEYWORDS = frozenset((
    "break", "case", "chan", "const", "continue", "default", "defer", "else", "fallthrough", "for", "func", "go",
    "goto", "if", "import", "interface", "map", "package", "range", "return", "select", "struct", "switch", "type",
    "var",
))
INITIALISMS = {"id": "ID", "xml": "XML", "ip": "IP", "tcp": "TCP", "gps": "GPS", "io": "IO"}
GO_TYPE = {"BYTE": "uint8", "BOOL": "bool", "INT16": "int16", "INT": "int32", "DOUBLE": "float64",
           "STRING": "string", "XML": "string"}
# Names the runtime declares: an enum constant that would clash is prefixed with its type's name.
RUNTIME_NAMES = frozenset((
    "DefaultMaxLength", "FieldType", "Field", "Layout", "Direction", "Request", "Reply", "Telegram", "ProtocolError",
    "FrameData", "EncodeData", "Encode", "DecodeData", "Decoder", "NewDecoder", "DecodeFrame", "Dump", "Client",
    "Dial",
))
HEAD = banner("// ")
TYPE_CONST = {"BYTE": "FieldByte", "BOOL": "FieldBool", "INT16": "FieldInt16", "INT": "FieldInt",
              "DOUBLE": "FieldDouble", "STRING": "FieldString", "XML": "FieldXML", "GROUP": "FieldGroup"}


def go_name(name: str) -> str:
    return "".join(INITIALISMS.get(w.lower(), w[:1].upper() + w[1:].lower()) for w in words(name))


def param(name: str) -> str:
    p = go_name(name)
    p = p[:1].lower() + p[1:] if not p.isupper() else p.lower()
    return p + "_" if p in KEYWORDS else p


def _enum_consts() -> dict[tuple[str, str], str]:
    plain: dict[str, list[str]] = {}
    for name, e in enums().items():
        for value in e.values:
            plain.setdefault(pascal(value), []).append(name)
    taken = RUNTIME_NAMES | set(item_types()) | set(enums())
    out = {}
    for name, e in enums().items():
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


def _type(f: Field) -> str:
    if f.is_group:
        return f"[]{f.item}"
    base = f.enum or GO_TYPE[f.type]
    return f"[{f.repeat}]{base}" if f.repeat else base


def _to_value(f: Field, expr: str) -> str:
    if f.is_group:
        return f"groupToValues({expr})"
    if f.repeat:
        return f"intsToValues({expr}[:])"
    if f.type == "BOOL":
        return f"b2i({expr})"
    if f.type in ("DOUBLE", "STRING", "XML"):
        return expr
    return f"int64({expr})"


def _from_value(f: Field, target: str, v: str) -> str:
    if f.is_group:
        return f"{target} = valuesToGroup[{f.item}]({v})"
    if f.repeat:
        return f"valuesToInts({v}, {target}[:])"
    if f.type == "BOOL":
        return f"{target} = {v}.(int64) != 0"
    if f.type == "DOUBLE":
        return f"{target} = {v}.(float64)"
    if f.is_text:
        return f"{target} = {v}.(string)"
    return f"{target} = {f.enum or GO_TYPE[f.type]}({v}.(int64))"


def _desc(f: Field) -> str:
    parts = [f'Name: "{f.name}"', f"Type: {TYPE_CONST[f.type]}"]
    if f.repeat:
        parts.append(f"Repeat: {f.repeat}")
    if f.const is not None:
        parts.append(f"HasConst: true, Const: {f.const}")
    if f.min is not None:
        parts.append(f"HasMin: true, Min: {f.min}")
    if f.max is not None:
        parts.append(f"HasMax: true, Max: {f.max}")
    if f.allowed is not None:
        parts.append(f"Allowed: []int64{{{', '.join(map(str, f.allowed))}}}")
    if f.is_group:
        parts.append(f"Fields: fields{f.item}, ItemMin: {f.item_min}")
    if f.run:
        parts.append(f"Run: {f.run}")
    return "{" + ", ".join(parts) + "}"


def _table(fields: tuple[Field, ...]) -> str:
    if not fields:
        return "nil"
    return "[]Field{\n" + "".join(f"\t{_desc(f)},\n" for f in fields) + "}"


def _struct_fields(fields: tuple[Field, ...]) -> list[str]:
    # Doc comments above each field: gofmt then aligns nothing, so the output is gofmt-clean as written.
    return [f"\t// {field_doc(f)}\n\t{go_name(f.name)} {_type(f)}" for f in fields if f.user]


def _conversions(recv: str, fields: tuple[Field, ...]) -> tuple[str, str]:
    user = [f for f in fields if f.user]
    values = ", ".join(_to_value(f, f"{recv}.{go_name(f.name)}") for f in user)
    sets = "".join(f"\t{_from_value(f, f'{recv}.{go_name(f.name)}', f'v[{i}]')}\n" for i, f in enumerate(user))
    return values, sets


def _func(signature: str, body: str) -> str:
    # Always multi-line: gofmt aligns consecutive one-line functions and breaks long ones.
    return f"func {signature} {{\n{body}}}\n" if body else f"func {signature} {{}}\n"


def _telegram(m: Message) -> str:
    t = m.type_name
    out = [f"// {t} is {m.name} ({m.direction}, id {m.id}): {doc_line(m.summary)} [guide {doc_line(m.section)}]"]
    if m.opaque:
        out += [f"type {t} struct {{\n\t// Payload is the bytes after the identifier (layout unknown).\n"
                f"\tPayload []byte\n}}\n",
                f"var layout{t} = Layout{{Opaque: true}}\n",
                _func(f"(t *{t}) Values() []any", "\treturn []any{t.Payload}\n"),
                _func(f"(t *{t}) setValues(v []any)", "\tt.Payload = v[0].([]byte)\n")]
    else:
        body = _struct_fields(m.fields)
        out.append(f"type {t} struct {{\n" + "\n".join(body) + "\n}\n" if body else f"type {t} struct{{}}\n")
        out.append(f"var layout{t} = Layout{{Fields: {_table(m.fields)}}}\n")
        values, sets = _conversions("t", m.fields)
        out.append(_func(f"(t *{t}) Values() []any", f"\treturn []any{{{values}}}\n"))
        out.append(_func(f"(t *{t}) setValues(v []any)", sets))
    direction = "Request" if m.direction == "request" else "Reply"
    out += [_func(f"(*{t}) TelegramID() uint8", f"\treturn {m.id}\n"),
            _func(f"(*{t}) TelegramName() string", f'\treturn "{m.name}"\n'),
            _func(f"(*{t}) TelegramDirection() Direction", f"\treturn {direction}\n"),
            _func(f"(*{t}) TelegramLayout() *Layout", f"\treturn &layout{t}\n")]
    return "\n".join(out)


def _protocol() -> str:
    out = [HEAD, "// Enums, group items and telegram types of the PlatformCtrl protocol (guide 6.3, 6.4).\n",
           "package platformctrl\n"]
    consts = _enum_consts()
    for name, e in enums().items():
        out.append(f"// {name}: {doc_line(e.description)} [guide {doc_line(e.section)}]\ntype {name} int32\n")
        out.append(f"// The values of {name}.\nconst (")
        out += [f"\t// {consts[(name, k)]} is {k}.\n\t{consts[(name, k)]} {name} = {v}" for k, v in e.values.items()]
        out.append(")\n")
    for name, fields in item_types().items():
        out.append(f"// {name} is one item of a repeated group.\ntype {name} struct {{")
        out += _struct_fields(fields)
        out.append("}\n")
        out.append(f"var fields{name} = {_table(fields)}\n")
        values, sets = _conversions("p", fields)
        out.append(_func(f"(p *{name}) values() []any", f"\treturn []any{{{values}}}\n"))
        out.append(_func(f"(p *{name}) setValues(v []any)", sets))
    for direction in ("request", "reply"):
        for m in messages(direction):
            out.append(_telegram(m))
    for direction, func in (("request", "newRequest"), ("reply", "newReply")):
        out.append(f"func {func}(id uint8) Telegram {{\n\tswitch id {{")
        out += [f"\tcase {m.id}:\n\t\treturn &{m.type_name}{{}}" for m in messages(direction)]
        out.append("\t}\n\treturn nil\n}\n")
    return "\n".join(out).rstrip("\n") + "\n"


def method_name(m: Message) -> str:
    return go_name(m.base)


def _methods() -> str:
    out = []
    for c in commands():
        m = c.request
        params, inits = [], []
        if m.opaque:
            params.append("payload []byte")
            inits.append("Payload: payload")
        for f in m.user_fields:
            params.append(f"{param(f.name)} {_type(f)}")
            inits.append(f"{go_name(f.name)}: {param(f.name)}")
        req = f"&{m.type_name}{{{', '.join(inits)}}}"
        doc = f"// {method_name(m)} sends {m.name} (id {m.id}): {doc_line(m.summary)}"
        if c.reply is None:
            out.append(f"{doc}\nfunc (c *Client) {method_name(m)}({', '.join(params)}) error {{\n"
                       f"\treturn c.Send({req})\n}}\n")
        else:
            r = c.reply.type_name
            out.append(f"{doc}\nfunc (c *Client) {method_name(m)}({', '.join(params)}) (*{r}, error) {{\n"
                       f"\tt, err := c.Request({req}, {m.id})\n\tif err != nil {{\n\t\treturn nil, err\n\t}}\n"
                       f"\treturn t.(*{r}), nil\n}}\n")
    return "\n".join(out).rstrip("\n")


BUILD_SH = """#!/bin/sh
{banner}# sh build.sh: build the package and the programs into build/ (Go 1.19+, no dependencies).
set -e
cd "$(dirname "$0")"
export GOTOOLCHAIN="${{GOTOOLCHAIN:-local}}"
[ -n "$GOCACHE" ] || [ -n "$HOME" ] || export GOCACHE="${{TMPDIR:-/tmp}}/go-build-cache"
go build -o build/ ./cmd/smoke ./cmd/vectors
"""
SMOKE_SH = """#!/bin/sh
{banner}# sh smoke.sh HOST PORT: build, then connect, init and print the position as one JSON line.
set -e
cd "$(dirname "$0")"
sh build.sh
exec ./build/smoke "$1" "$2"
"""
VECTORS_SH = """#!/bin/sh
{banner}# sh vectors.sh FILE: build, then check every vector of FILE (python -m clients.stubgen.vectors writes it).
set -e
FILE="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
cd "$(dirname "$0")"
sh build.sh
exec ./build/vectors "$FILE"
"""


README = readme(
    title="Go",
    build=(
        "`go build ./cmd/...`, Go 1.19+"
    ),
    snippet_lang="go",
    snippet="""
c, err := platformctrl.Dial("192.168.0.10:10002", 10*time.Second)
if err != nil {
	return err
}
defer c.Close()
_ = c.ConnectToPltf()
_ = c.SetMode(platformctrl.ModeMotionVel)
pos, err := c.GetPosition() // *GetPositionReply
""",
    notes=(
        "Match errors with `errors.Is(err, platformctrl.ErrTruncated)` (or `ErrRemoteProtocolError`). The "
        "code is gofmt-clean."
    ),
)


def render() -> dict[str, str]:
    return {
        "README.md": README,
        "go.mod": HEAD + "module platformctrl\n\ngo 1.19\n",
        "wire.go": HEAD + fill(template("go", "wire.go.tmpl"), ERRORS=_errors()),
        "protocol.go": _protocol(),
        "client.go": HEAD + fill(template("go", "client.go.tmpl"), METHODS=_methods()),
        "cmd/smoke/main.go": HEAD + template("go", "smoke.go.tmpl"),
        "cmd/vectors/main.go": HEAD + template("go", "vectors.go.tmpl"),
        "build.sh": BUILD_SH.format(banner=HEAD.replace("// ", "# ")),
        "smoke.sh": SMOKE_SH.format(banner=HEAD.replace("// ", "# ")),
        "vectors.sh": VECTORS_SH.format(banner=HEAD.replace("// ", "# ")),
        ".gitignore": HEAD.replace("// ", "# ") + "build/\n",
    }
