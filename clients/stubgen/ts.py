"""TypeScript client for Node (npm + tsc, no runtime dependencies): classes, numeric enums, item interfaces."""

from __future__ import annotations

from clients.stubgen import banner, fill, readme, template
from clients.stubgen.model import (
    ERRORS,
    Field,
    Message,
    camel,
    commands,
    doc_line,
    enums,
    field_doc,
    item_types,
    messages,
    snake,
)

RESERVED = frozenset((
    "break", "case", "catch", "class", "const", "continue", "debugger", "default", "delete", "do", "else", "enum",
    "export", "extends", "false", "finally", "for", "function", "if", "import", "in", "instanceof", "new", "null",
    "return", "super", "switch", "this", "throw", "true", "try", "typeof", "var", "void", "while", "with", "let",
    "static", "yield", "await", "implements", "interface", "package", "private", "protected", "public",
))
CLIENT_NAMES = frozenset(("connect", "close", "send", "receive", "request"))
TS_TYPE = {"BYTE": "number", "BOOL": "boolean", "INT16": "number", "INT": "number", "DOUBLE": "number",
           "STRING": "string", "XML": "string"}
TYPE_MEMBER = {"BYTE": "Byte", "BOOL": "Bool", "INT16": "Int16", "INT": "Int", "DOUBLE": "Double",
               "STRING": "String", "XML": "Xml", "GROUP": "Group"}
HEAD = banner("// ")
# TypeScript versions pinned for reproducible builds (typescript has no dependencies of its own).
DEV_DEPENDENCIES = {"@types/node": "20.19.0", "typescript": "5.9.3"}


def param(name: str) -> str:
    p = camel(name)
    return p + "_" if p in RESERVED else p


def _errors() -> str:
    out = []
    for name, parent, doc in ERRORS:
        base = parent or "Error"
        out.append(f"/** {doc} */\nexport class {name} extends {base} {{\n  constructor(message: string) {{\n"
                   f'    super(message);\n    this.name = "{name}";\n  }}\n}}\n')
    return "\n".join(out).rstrip("\n")


def _type(f: Field) -> str:
    if f.is_group:
        return f"{f.item}[]"
    base = f.enum or TS_TYPE[f.type]
    return f"{base}[]" if f.repeat else base


def _default(f: Field) -> str:
    if f.is_group:
        return "[]"
    if f.enum:
        single = f"{f.enum}.{next(iter(enums()[f.enum].values))}"
    else:
        single = {"boolean": "false", "string": '""'}.get(TS_TYPE[f.type], "0")
    return "[" + ", ".join([single] * f.repeat) + "]" if f.repeat else single


def _desc(f: Field) -> str:
    parts = [f'name: "{f.name}"', f'prop: "{camel(f.name)}"', f"type: FieldType.{TYPE_MEMBER[f.type]}"]
    if f.repeat:
        parts.append(f"repeat: {f.repeat}")
    if f.const is not None:
        parts.append(f"const: {f.const}")
    if f.min is not None:
        parts.append(f"min: {f.min}")
    if f.max is not None:
        parts.append(f"max: {f.max}")
    if f.allowed is not None:
        parts.append(f"allowed: [{', '.join(map(str, f.allowed))}]")
    if f.is_group:
        parts.append(f"fields: {snake(f.item or '').upper()}_FIELDS, itemMin: {f.item_min}")
    if f.run:
        parts.append(f"run: {f.run}")
    return "{ " + ", ".join(parts) + " }"


def _table(fields: tuple[Field, ...], indent: str) -> str:
    if not fields:
        return "[]"
    return "[\n" + "".join(f"{indent}  {_desc(f)},\n" for f in fields) + f"{indent}]"


def _telegram(m: Message) -> str:
    t = m.type_name
    direction = m.direction
    lines = [f"/** {m.name} ({direction}, id {m.id}): {doc_line(m.summary)} [guide {doc_line(m.section)}] */",
             f"export class {t} extends Telegram {{",
             f"  static readonly ID = {m.id};", f'  static readonly NAME = "{m.name}";',
             f'  static readonly DIRECTION: Direction = "{direction}";']
    if m.opaque:
        lines += ["  static readonly LAYOUT: Layout = { opaque: true, fields: [] };",
                  "  /** The bytes after the identifier (layout unknown). */",
                  "  payload: Uint8Array = new Uint8Array(0);"]
    else:
        lines.append(f"  static readonly LAYOUT: Layout = {{ opaque: false, fields: {_table(m.fields, '  ')} }};")
        for f in m.user_fields:
            lines += [f"  /** {field_doc(f)} */", f"  {camel(f.name)}: {_type(f)} = {_default(f)};"]
    lines += ["", f"  constructor(init: Partial<{t}> = {{}}) {{", "    super();", "    Object.assign(this, init);",
              "  }", "}\n"]
    return "\n".join(lines)


def _protocol() -> str:
    out = [HEAD, "/** Enums, group items and telegram classes of the PlatformCtrl protocol (guide 6.3, 6.4). */\n",
           'import { Direction, Field, FieldType, Layout, Telegram, TelegramClass } from "./wire";\n']
    for name, e in enums().items():
        out.append(f"/** {doc_line(e.description)} [guide {doc_line(e.section)}] */\nexport enum {name} {{")
        out += [f"  {k} = {v}," for k, v in e.values.items()]
        out.append("}\n")
    for name, fields in item_types().items():
        out.append(f"/** One item of a repeated group. */\nexport interface {name} {{")
        for f in fields:
            if f.user:
                out += [f"  /** {field_doc(f)} */", f"  {camel(f.name)}: {_type(f)};"]
        out.append("}\n")
        out.append(f"const {snake(name).upper()}_FIELDS: Field[] = {_table(fields, '')};\n")
    for direction in ("request", "reply"):
        for m in messages(direction):
            out.append(_telegram(m))
    for direction, const in (("request", "REQUESTS"), ("reply", "REPLIES")):
        out.append(f"/** Every {direction} class, by identifier. */")
        out.append(f"export const {const}: ReadonlyMap<number, TelegramClass> = new Map<number, TelegramClass>([")
        out += [f"  [{m.id}, {m.type_name}]," for m in messages(direction)]
        out.append("]);\n")
    return "\n".join(out).rstrip("\n") + "\n"


def method_name(m: Message) -> str:
    name = camel(m.base)
    return name + "_" if name in CLIENT_NAMES else name


def _methods() -> str:
    out = []
    for c in commands():
        m = c.request
        params, inits = [], []
        if m.opaque:
            params.append("payload: Uint8Array = new Uint8Array(0)")
            inits.append("payload")
        for f in m.user_fields:
            prop, arg = camel(f.name), param(f.name)
            named = f.item if f.is_group else f.enum
            ptype = _type(f).replace(named, f"p.{named}") if named else _type(f)
            params.append(f"{arg}: {ptype}")
            inits.append(prop if prop == arg else f"{prop}: {arg}")
        req = f"new p.{m.type_name}({{ {', '.join(inits)} }})" if inits else f"new p.{m.type_name}()"
        doc = f"  /** {m.name} (id {m.id}): {doc_line(m.summary)} */"
        if c.reply is None:
            out.append(f"{doc}\n  {method_name(m)}({', '.join(params)}): Promise<void> {{\n"
                       f"    return this.send({req});\n  }}\n")
        else:
            r = c.reply.type_name
            out.append(f"{doc}\n  {method_name(m)}({', '.join(params)}): Promise<p.{r}> {{\n"
                       f"    return this.request({req}, p.{r});\n  }}\n")
    return "\n" + "\n".join(out).rstrip("\n")


INDEX = """{banner}/** PlatformCtrl socket protocol client (generated): `import {{ Client }} from "platformctrl"`. */

export * from "./wire";
export * from "./protocol";
export * from "./codec";
export {{ Client }} from "./client";
"""
TSCONFIG = """{banner}{{
  "compilerOptions": {{
    "target": "ES2022",
    "module": "commonjs",
    "lib": ["ES2022"],
    "types": ["node"],
    "strict": true,
    "declaration": true,
    "outDir": "dist",
    "rootDir": "src",
    "skipLibCheck": true
  }},
  "include": ["src"]
}}
"""
BUILD_SH = """#!/bin/sh
{banner}# sh build.sh: npm install (typescript, @types/node; from the npm registry when not cached), then tsc.
set -e
cd "$(dirname "$0")"
[ -x node_modules/.bin/tsc ] || npm install --no-audit --no-fund --prefer-offline --loglevel=error >/dev/null
if [ ! -f dist/.stamp ] || [ -n "$(find src tsconfig.json -newer dist/.stamp)" ]; then
  node_modules/.bin/tsc -p .
  touch dist/.stamp
fi
"""
SMOKE_SH = """#!/bin/sh
{banner}# sh smoke.sh HOST PORT: build, then connect, init and print the position as one JSON line.
set -e
cd "$(dirname "$0")"
sh build.sh
exec node dist/smoke.js "$1" "$2"
"""
VECTORS_SH = """#!/bin/sh
{banner}# sh vectors.sh FILE: build, then check every vector of FILE (python -m clients.stubgen.vectors writes it).
set -e
FILE="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
cd "$(dirname "$0")"
sh build.sh
exec node dist/vectors.js "$FILE"
"""


def _package() -> str:
    deps = ",\n".join(f'    "{k}": "{v}"' for k, v in DEV_DEPENDENCIES.items())
    note = banner("").strip().replace('"', "'")
    return ("{\n" f'  "name": "platformctrl",\n  "version": "0.1.0",\n  "private": true,\n'
            f'  "description": "PlatformCtrl socket protocol client. {note}",\n'
            '  "main": "dist/index.js",\n  "types": "dist/index.d.ts",\n'
            '  "scripts": {\n    "build": "tsc -p .",\n    "smoke": "node dist/smoke.js",\n'
            '    "vectors": "node dist/vectors.js"\n  },\n'
            f'  "devDependencies": {{\n{deps}\n  }}\n}}\n')


README = readme(
    title="TypeScript (Node)",
    build=(
        "`npm install` then `tsc`; typescript and @types/node are the only (dev) dependencies"
    ),
    snippet_lang="ts",
    snippet="""
import { Client, MotionMode } from "platformctrl";

const client = await Client.connect("192.168.0.10", 10002);
await client.connectToPltf();
await client.setMode(MotionMode.MODE_MOTION_VEL);
const pos = await client.getPosition(); // GetPositionReply
client.close();
""",
    notes=(
        "Methods return promises; errors are classes (`instanceof Truncated`). `decodeFrame`, `encode` and "
        "`TelegramDecoder` are sans-IO."
    ),
)


def render() -> dict[str, str]:
    sh = HEAD.replace("// ", "# ")
    return {
        "README.md": README,
        "package.json": _package(),
        "tsconfig.json": TSCONFIG.format(banner=HEAD),
        "src/index.ts": INDEX.format(banner=HEAD),
        "src/wire.ts": HEAD + fill(template("typescript", "wire.ts.tmpl"), ERRORS=_errors()),
        "src/protocol.ts": _protocol(),
        "src/codec.ts": HEAD + template("typescript", "codec.ts.tmpl"),
        "src/client.ts": HEAD + fill(template("typescript", "client.ts.tmpl"), METHODS=_methods()),
        "src/smoke.ts": HEAD + template("typescript", "smoke.ts.tmpl"),
        "src/vectors.ts": HEAD + template("typescript", "vectors.ts.tmpl"),
        "build.sh": BUILD_SH.format(banner=sh),
        "smoke.sh": SMOKE_SH.format(banner=sh),
        "vectors.sh": VECTORS_SH.format(banner=sh),
        ".gitignore": sh + "node_modules/\ndist/\npackage-lock.json\n",
    }
