"""Rust client: crate ``platformctrl`` (no dependencies), typed structs, enums, ``Request``/``Reply`` sets."""

from __future__ import annotations

from clients.stubgen import banner, fill, readme, template
from clients.stubgen.model import (
    ERRORS,
    LEAF_ERRORS,
    Field,
    Message,
    commands,
    doc_line,
    enums,
    field_doc,
    item_types,
    messages,
    pascal,
    snake,
)

KEYWORDS = frozenset((
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for", "if", "impl",
    "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return", "self", "static", "struct",
    "super", "trait", "true", "type", "unsafe", "use", "where", "while", "async", "await", "dyn", "abstract",
    "become", "box", "do", "final", "macro", "override", "priv", "typeof", "unsized", "virtual", "yield", "try",
))
CLIENT_NAMES = frozenset(("connect", "send", "receive", "request"))
RUST_TYPE = {"BYTE": "u8", "BOOL": "bool", "INT16": "i16", "INT": "i32", "DOUBLE": "f64", "STRING": "String",
             "XML": "String"}
TYPE_VARIANT = {"BYTE": "Byte", "BOOL": "Bool", "INT16": "Int16", "INT": "Int", "DOUBLE": "Double",
                "STRING": "String", "XML": "Xml", "GROUP": "Group"}
HEAD = banner("// ")


def ident(name: str) -> str:
    return f"r#{name}" if name in KEYWORDS else name


def _errors() -> str:
    parents = {name: parent for name, parent, _ in ERRORS}
    docs = {name: doc for name, _, doc in ERRORS}
    out = ["/// The error family of the protocol (leaf classes), and `Io` for the client's socket errors.",
           "#[derive(Clone, Copy, Debug, PartialEq, Eq)]", "pub enum ErrorKind {"]
    for name in LEAF_ERRORS:
        out += [f"    /// {docs[name]}", f"    {name},"]
    out += ["    /// A socket error of the client, or the server closed the connection.", "    Io,", "}", "",
            "impl ErrorKind {", "    /// The class name, as the vector files write it.",
            "    pub fn name(self) -> &'static str {", "        match self {"]
    out += [f'            ErrorKind::{name} => "{name}",' for name in LEAF_ERRORS]
    out += ['            ErrorKind::Io => "Io",', "        }", "    }", "",
            "    /// The peer sent bytes the protocol does not allow (RemoteProtocolError).",
            "    pub fn is_remote(self) -> bool {"]
    remote = [n for n in LEAF_ERRORS if parents[n] == "RemoteProtocolError"]
    out += ["        matches!(", "            self,", f"            ErrorKind::{remote[0]}"]
    out += [f"                | ErrorKind::{n}" for n in remote[1:]]
    out += ["        )", "    }", "}"]
    return "\n".join(out)


def _type(f: Field) -> str:
    if f.is_group:
        return f"Vec<{f.item}>"
    base = f.enum or RUST_TYPE[f.type]
    return f"[{base}; {f.repeat}]" if f.repeat else base


def _desc(f: Field) -> str:
    out = f'field("{f.name}", FieldType::{TYPE_VARIANT[f.type]})'
    if f.repeat:
        out += f".repeat({f.repeat})"
    if f.const is not None:
        out += f".constant({f.const})"
    if f.min is not None:
        out += f".min({f.min})"
    if f.max is not None:
        out += f".max({f.max})"
    if f.allowed is not None:
        out += f".allowed(&[{', '.join(map(str, f.allowed))}])"
    if f.is_group:
        out += f".group({snake(f.item or '').upper()}_FIELDS, {f.item_min})"
    if f.run:
        out += f".run({f.run})"
    return out


def _table(fields: tuple[Field, ...]) -> str:
    if not fields:
        return "&[]"
    return "&[\n" + "".join(f"        {_desc(f)},\n" for f in fields) + "    ]"


def _struct(name: str, doc: str, fields: tuple[Field, ...], derive: str) -> str:
    user = [f for f in fields if f.user]
    out = [f"/// {doc}", f"#[derive({derive})]"]
    if not user:
        return "\n".join([*out, f"pub struct {name} {{}}\n"])
    out.append(f"pub struct {name} {{")
    for f in user:
        out += [f"    /// {field_doc(f)}", f"    pub {ident(f.name)}: {_type(f)},"]
    return "\n".join([*out, "}\n"])


def _conversions(fields: tuple[Field, ...]) -> tuple[str, str]:
    user = [f for f in fields if f.user]
    to = ", ".join(f"self.{ident(f.name)}.to_value()" for f in user)
    if not user:
        return "vec![]", "Self {}"
    sets = "".join(f"            {ident(f.name)}: take(&mut it),\n" for f in user)
    return f"vec![{to}]", f"let mut it = values.into_iter();\n        Self {{\n{sets}        }}"


def _telegram(m: Message) -> str:
    t = m.type_name
    doc = f"{m.name} ({m.direction}, id {m.id}): {doc_line(m.summary)} [guide {doc_line(m.section)}]"
    direction = "Request" if m.direction == "request" else "Reply"
    if m.opaque:
        struct = (f"/// {doc}\n#[derive(Clone, Debug, Default, PartialEq)]\npub struct {t} {{\n"
                  "    /// The bytes after the identifier (layout unknown).\n    pub payload: Vec<u8>,\n}\n")
        layout, to, frm = "Layout { opaque: true, fields: &[] }", "vec![self.payload.to_value()]", \
            "let mut it = values.into_iter();\n        Self { payload: take(&mut it) }"
    else:
        struct = _struct(t, doc, m.fields, "Clone, Debug, Default, PartialEq")
        layout = f"Layout {{ opaque: false, fields: {_table(m.fields)} }}"
        to, frm = _conversions(m.fields)
    values = "values" if m.opaque or m.user_fields else "_values"
    return (f"{struct}\nimpl Message for {t} {{\n    const ID: u8 = {m.id};\n"
            f'    const NAME: &\'static str = "{m.name}";\n    const DIRECTION: Direction = Direction::{direction};\n'
            f"    const LAYOUT: Layout = {layout};\n\n"
            f"    fn to_values(&self) -> Vec<Value> {{\n        {to}\n    }}\n\n"
            f"    fn from_values({values}: Vec<Value>) -> Self {{\n        {frm}\n    }}\n}}\n")


def _protocol() -> str:
    out = [HEAD, "//! Enums, group items and telegram types of the PlatformCtrl protocol (guide 6.3, 6.4).\n",
           "#![allow(clippy::all)]\n", "use crate::wire::*;\n"]
    for name, e in enums().items():
        out += [f"/// {doc_line(e.description)} [guide {doc_line(e.section)}]",
                "#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]", "#[repr(i32)]", f"pub enum {name} {{"]
        for i, (k, v) in enumerate(e.values.items()):
            out += [f"    /// {k}", *(["    #[default]"] if i == 0 else []), f"    {pascal(k)} = {v},"]
        out += ["}\n", f"impl {name} {{", "    /// The value with this number, if the guide defines one.",
                "    pub fn from_i64(v: i64) -> Option<Self> {", "        match v {"]
        out += [f"            {v} => Some({name}::{pascal(k)})," for k, v in e.values.items()]
        out += ["            _ => None,", "        }", "    }", "}\n"]
    out.append(f"enum_value!({', '.join(enums())});\n")
    for name, fields in item_types().items():
        out.append(_struct(name, "One item of a repeated group.", fields, "Clone, Debug, Default, PartialEq"))
        table = _table(fields).replace("\n    ", "\n")
        out.append(f"const {snake(name).upper()}_FIELDS: &[Field] = {table};\n")
        to, frm = _conversions(fields)
        out.append(f"impl Item for {name} {{\n    fn to_values(&self) -> Vec<Value> {{\n        {to}\n    }}\n\n"
                   f"    fn from_values(values: Vec<Value>) -> Self {{\n        {frm}\n    }}\n}}\n")
    for direction in ("request", "reply"):
        for m in messages(direction):
            out.append(_telegram(m))
    for direction, set_name in (("request", "Request"), ("reply", "Reply")):
        out.append(f"telegram_set! {{\n    /// Every {direction} telegram, by identifier.\n    {set_name}, {set_name},")
        out += [f"    {pascal(m.base)}({m.type_name}) = {m.id}," for m in messages(direction)]
        out.append("}\n")
    return "\n".join(out).rstrip("\n") + "\n"


def method_name(m: Message) -> str:
    name = snake(m.base)
    return name + "_" if name in KEYWORDS or name in CLIENT_NAMES else name


def _methods() -> str:
    out = []
    for c in commands():
        m = c.request
        params, inits = ["&mut self"], []
        if m.opaque:
            params.append("payload: &[u8]")
            inits.append("payload: payload.to_vec()")
        for f in m.user_fields:
            name = ident(f.name)
            if f.is_group:
                params.append(f"{name}: &[{f.item}]")
                inits.append(f"{name}: {name}.to_vec()")
            elif f.is_text:
                params.append(f"{name}: &str")
                inits.append(f"{name}: {name}.to_string()")
            else:
                params.append(f"{name}: {_type(f)}")
                inits.append(name)
        req = f"&{m.type_name} {{ {', '.join(inits)} }}" if inits else f"&{m.type_name} {{}}"
        doc = f"    /// {m.name} (id {m.id}): {doc_line(m.summary)}"
        if c.reply is None:
            out.append(f"{doc}\n    pub fn {method_name(m)}({', '.join(params)}) -> Result<(), Error> {{\n"
                       f"        self.send({req})\n    }}\n")
        else:
            r = c.reply.type_name
            out.append(f"{doc}\n    pub fn {method_name(m)}({', '.join(params)}) -> Result<{r}, Error> {{\n"
                       f"        match self.request({req})? {{\n"
                       f"            Reply::{pascal(c.reply.base)}(r) => Ok(r),\n"
                       "            other => Err(Error::new(ErrorKind::UnknownTelegram, "
                       'format!("got {:?}", other))),\n'
                       "        }\n    }\n")
    return "\n" + "\n".join(out).rstrip("\n")


CARGO = """{banner}[package]
name = "platformctrl"
version = "0.1.0"
edition = "2021"
description = "PlatformCtrl socket protocol client (generated, standard library only)"
publish = false

[dependencies]
"""
LIB = """{banner}//! PlatformCtrl socket protocol client (generated): framing, typed telegrams, a streaming decoder
//! and a blocking client with one method per command.

// The two modules written per telegram are left as generated; wire.rs and the programs are rustfmt-clean.
#[rustfmt::skip]
mod client;
#[rustfmt::skip]
mod protocol;
mod wire;

pub use client::Client;
pub use protocol::*;
pub use wire::*;
"""
BUILD_SH = """#!/bin/sh
{banner}# sh build.sh: build the crate and its two programs (cargo, no dependencies: works offline).
set -e
cd "$(dirname "$0")"
cargo build --quiet --offline --bins
"""
SMOKE_SH = """#!/bin/sh
{banner}# sh smoke.sh HOST PORT: build, then connect, init and print the position as one JSON line.
set -e
cd "$(dirname "$0")"
sh build.sh
exec "${{CARGO_TARGET_DIR:-target}}/debug/smoke" "$1" "$2"
"""
VECTORS_SH = """#!/bin/sh
{banner}# sh vectors.sh FILE: build, then check every vector of FILE (python -m clients.stubgen.vectors writes it).
set -e
FILE="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
cd "$(dirname "$0")"
sh build.sh
exec "${{CARGO_TARGET_DIR:-target}}/debug/vectors" "$FILE"
"""


README = readme(
    title="Rust",
    build=(
        "`cargo build`, no dependencies"
    ),
    snippet_lang="rust",
    snippet="""
let mut client = platformctrl::Client::connect(("192.168.0.10", 10002), Some(Duration::from_secs(10)))?;
client.connect_to_pltf()?;
client.set_mode(platformctrl::MotionMode::ModeMotionVel)?;
let pos = client.get_position()?; // GetPositionReply
""",
    notes=(
        "`decode_frame::<Reply>(bytes)` and `Decoder::<Reply>::new()` are sans-IO; `Request`/`Reply` are "
        "enums of every telegram. `Error::kind` names the error class."
    ),
)


def render() -> dict[str, str]:
    sh = HEAD.replace("// ", "# ")
    return {
        "README.md": README,
        "Cargo.toml": CARGO.format(banner=sh),
        "src/lib.rs": LIB.format(banner=HEAD),
        "src/wire.rs": HEAD + fill(template("rust", "wire.rs.tmpl"), ERRORS=_errors()),
        "src/protocol.rs": _protocol(),
        "src/client.rs": HEAD + fill(template("rust", "client.rs.tmpl"), METHODS=_methods()),
        "src/bin/smoke.rs": HEAD + template("rust", "smoke.rs.tmpl"),
        "src/bin/vectors.rs": HEAD + template("rust", "vectors.rs.tmpl"),
        "build.sh": BUILD_SH.format(banner=sh),
        "smoke.sh": SMOKE_SH.format(banner=sh),
        "vectors.sh": VECTORS_SH.format(banner=sh),
        ".gitignore": sh + "target/\nCargo.lock\n",
    }
