"""Rust client: crate ``platformctrl`` (no dependencies), typed structs, enums, ``Request``/``Reply`` sets."""

from __future__ import annotations

from pltf.stubgen import banner, fill, model, readme, template
from pltf.stubgen.model import ERRORS, LEAF_ERRORS, Field, Message, doc_line, pascal, snake
from pltf.stubgen.renderer import BUILDER, Spelling, arguments, convert, methods, protocol, scripts, static

KEYWORDS = frozenset(
    (
        "as",
        "break",
        "const",
        "continue",
        "crate",
        "else",
        "enum",
        "extern",
        "false",
        "fn",
        "for",
        "if",
        "impl",
        "in",
        "let",
        "loop",
        "match",
        "mod",
        "move",
        "mut",
        "pub",
        "ref",
        "return",
        "self",
        "static",
        "struct",
        "super",
        "trait",
        "true",
        "type",
        "unsafe",
        "use",
        "where",
        "while",
        "async",
        "await",
        "dyn",
        "abstract",
        "become",
        "box",
        "do",
        "final",
        "macro",
        "override",
        "priv",
        "typeof",
        "unsized",
        "virtual",
        "yield",
        "try",
    )
)
CLIENT_NAMES = frozenset(("connect", "send", "receive", "request"))
RUST_TYPE = {
    "BYTE": "u8",
    "BOOL": "bool",
    "INT16": "i16",
    "INT": "i32",
    "DOUBLE": "f64",
    "STRING": "String",
    "XML": "String",
}
HEAD = banner("// ")


def ident(name: str) -> str:
    return f"r#{name}" if name in KEYWORDS else name


SPELLING = Spelling(
    scalars=RUST_TYPE,
    group="Vec<{item}>",
    array="[{base}; {repeat}]",
    head='field("{f.name}", FieldType::{type})',
    type_name=pascal,
    sep="",
    attrs={**BUILDER, "allowed": ".allowed(&[{allowed}])", "group": ".group({ITEM}_FIELDS, {f.item_min})"},
    empty="&[]",
    open="&[",
    close="{indent}]",
    step="    ",
    member="    /// {doc}\n    pub {name}: {type},",
    field_name=ident,
)
METHOD = (
    "    /// {m.name} (id {m.id}): {summary}\n    pub fn {name}({params}) -> Result<(), Error> {{\n"
    "        self.send({req})\n    }}\n",
    "    /// {m.name} (id {m.id}): {summary}\n    pub fn {name}({params}) -> Result<{reply}, Error> {{\n"
    "        match self.request({req})? {{\n            Reply::{variant}(r) => Ok(r),\n"
    '            other => Err(Error::new(ErrorKind::UnknownTelegram, format!("got {{:?}}", other))),\n'
    "        }}\n    }}\n",
)
# A client method's parameter and the request field it sets: slices and &str in, owned values in the request.
PARAM = {
    "group": "{n}: &[{item}]",
    "text": "{n}: &str",
    "array": "{n}: {t}",
    "int": "{n}: {t}",
    "BOOL": "{n}: {t}",
    "DOUBLE": "{n}: {t}",
}
INIT = {
    "group": "{n}: {n}.to_vec()",
    "text": "{n}: {n}.to_string()",
    "array": "{n}",
    "int": "{n}",
    "BOOL": "{n}",
    "DOUBLE": "{n}",
}


def _errors() -> str:
    parents = {name: parent for name, parent, _ in ERRORS}
    docs = {name: doc for name, _, doc in ERRORS}
    out = [
        "/// The error family of the protocol (leaf classes), and `Io` for the client's socket errors.",
        "#[derive(Clone, Copy, Debug, PartialEq, Eq)]",
        "pub enum ErrorKind {",
    ]
    for name in LEAF_ERRORS:
        out += [f"    /// {docs[name]}", f"    {name},"]
    out += [
        "    /// A socket error of the client, or the server closed the connection.",
        "    Io,",
        "}",
        "",
        "impl ErrorKind {",
        "    /// The class name, as the vector files write it.",
        "    pub fn name(self) -> &'static str {",
        "        match self {",
    ]
    out += [f'            ErrorKind::{name} => "{name}",' for name in LEAF_ERRORS]
    out += [
        '            ErrorKind::Io => "Io",',
        "        }",
        "    }",
        "",
        "    /// The peer sent bytes the protocol does not allow (RemoteProtocolError).",
        "    pub fn is_remote(self) -> bool {",
    ]
    remote = [n for n in LEAF_ERRORS if parents[n] == "RemoteProtocolError"]
    out += ["        matches!(", "            self,", f"            ErrorKind::{remote[0]}"]
    out += [f"                | ErrorKind::{n}" for n in remote[1:]]
    out += ["        )", "    }", "}"]
    return "\n".join(out)


def _struct(name: str, doc: str, fields: tuple[Field, ...], derive: str) -> str:
    user = [f for f in fields if f.user]
    out = [f"/// {doc}", f"#[derive({derive})]"]
    if not user:
        return "\n".join([*out, f"pub struct {name} {{}}\n"])
    out.append(f"pub struct {name} {{")
    return "\n".join([*out, *SPELLING.members(fields), "}\n"])


def _conversions(fields: tuple[Field, ...]) -> tuple[str, str]:
    user = [f for f in fields if f.user]
    to = ", ".join(f"self.{ident(f.name)}.to_value()" for f in user)
    if not user:
        return "vec![]", "Self {}"
    sets = "".join(f"            {ident(f.name)}: take(&mut it),\n" for f in user)
    return f"vec![{to}]", f"let mut it = values.into_iter();\n        Self {{\n{sets}        }}"


def _telegram(m: Message) -> str:
    t = m.type_name
    doc = m.doc
    direction = "Request" if m.direction == "request" else "Reply"
    if m.opaque:
        struct = (
            f"/// {doc}\n#[derive(Clone, Debug, Default, PartialEq)]\npub struct {t} {{\n"
            "    /// The bytes after the identifier (layout unknown).\n    pub payload: Vec<u8>,\n}\n"
        )
        layout, to, frm = (
            "Layout { opaque: true, fields: &[] }",
            "vec![self.payload.to_value()]",
            "let mut it = values.into_iter();\n        Self { payload: take(&mut it) }",
        )
    else:
        struct = _struct(t, doc, m.fields, "Clone, Debug, Default, PartialEq")
        layout = f"Layout {{ opaque: false, fields: {SPELLING.table(m.fields, '    ')} }}"
        to, frm = _conversions(m.fields)
    values = "values" if m.opaque or m.user_fields else "_values"
    return (
        f"{struct}\nimpl Message for {t} {{\n    const ID: u8 = {m.id};\n"
        f'    const NAME: &\'static str = "{m.name}";\n    const DIRECTION: Direction = Direction::{direction};\n'
        f"    const LAYOUT: Layout = {layout};\n\n"
        f"    fn to_values(&self) -> Vec<Value> {{\n        {to}\n    }}\n\n"
        f"    fn from_values({values}: Vec<Value>) -> Self {{\n        {frm}\n    }}\n}}\n"
    )


def _enum(name: str) -> str:
    values = model.enums()[name].values
    out = [
        f"/// {model.enum_doc(name)}",
        "#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]",
        "#[repr(i32)]",
        f"pub enum {name} {{",
    ]
    for i, (k, v) in enumerate(values.items()):
        out += [f"    /// {k}", *(["    #[default]"] if i == 0 else []), f"    {pascal(k)} = {v},"]
    out += [
        "}\n",
        f"impl {name} {{",
        "    /// The value with this number, if the guide defines one.",
        "    pub fn from_i64(v: i64) -> Option<Self> {",
        "        match v {",
    ]
    out += [f"            {v} => Some({name}::{pascal(k)})," for k, v in values.items()]
    return "\n".join([*out, "            _ => None,", "        }", "    }", "}\n"])


def _item(name: str, fields: tuple[Field, ...]) -> str:
    to, frm = _conversions(fields)
    return "\n".join(
        [
            _struct(name, "One item of a repeated group.", fields, "Clone, Debug, Default, PartialEq"),
            f"const {snake(name).upper()}_FIELDS: &[Field] = {SPELLING.table(fields)};\n",
            f"impl Item for {name} {{\n    fn to_values(&self) -> Vec<Value> {{\n        {to}\n    }}\n\n"
            f"    fn from_values(values: Vec<Value>) -> Self {{\n        {frm}\n    }}\n}}\n",
        ]
    )


def _registry(direction: str, telegrams: tuple[Message, ...]) -> str:
    set_name = "Request" if direction == "request" else "Reply"
    out = [f"telegram_set! {{\n    /// Every {direction} telegram, by identifier.\n    {set_name}, {set_name},"]
    out += [f"    {pascal(m.base)}({m.type_name}) = {m.id}," for m in telegrams]
    return "\n".join([*out, "}\n"])


def _protocol() -> str:
    head = [
        HEAD,
        "//! Enums, group items and telegram types of the PlatformCtrl protocol (guide 6.3, 6.4).\n",
        "#![allow(clippy::all)]\n",
        "use crate::wire::*;\n",
    ]
    enum_value = f"enum_value!({', '.join(model.enums())});\n"
    return protocol(head, _enum, _item, _telegram, _registry, after_enums=[enum_value])


def method_name(m: Message) -> str:
    return model.safe(snake(m.base), KEYWORDS | CLIENT_NAMES)


def _method(m: Message) -> dict[str, str]:
    params, inits = arguments(
        m,
        ("payload: &[u8]", "payload: payload.to_vec()"),
        lambda f: (convert(PARAM, f, n=ident(f.name), t=SPELLING.type(f)), convert(INIT, f, n=ident(f.name))),
    )
    return {
        "name": method_name(m),
        "params": ", ".join(["&mut self", *params]),
        "variant": pascal(m.base),
        "req": f"&{m.type_name} {{ {', '.join(inits)} }}" if inits else f"&{m.type_name} {{}}",
        "summary": doc_line(m.summary),
    }


README = readme("rust", "Rust", "`cargo build`, no dependencies")


def render() -> dict[str, str]:
    return {
        "README.md": README,
        "src/wire.rs": HEAD + fill(template("rust", "wire.rs.tmpl"), ERRORS=_errors()),
        "src/protocol.rs": _protocol(),
        "src/client.rs": HEAD + fill(template("rust", "client.rs.tmpl"), METHODS=methods(_method, METHOD)),
        **static(
            "rust",
            HEAD,
            {"src/lib.rs": "lib.rs.tmpl", "src/bin/smoke.rs": "smoke.rs.tmpl", "src/bin/vectors.rs": "vectors.rs.tmpl"},
        ),
        **static("rust", banner("# "), {"Cargo.toml": "Cargo.toml.tmpl"}),
        **scripts(
            "rust",
            "build the crate and its two programs (cargo, no dependencies: works offline).",
            '"${CARGO_TARGET_DIR:-target}/debug/smoke"',
            '"${CARGO_TARGET_DIR:-target}/debug/vectors"',
            "target/\nCargo.lock\n",
        ),
    }
