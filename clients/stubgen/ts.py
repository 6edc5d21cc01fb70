"""TypeScript client for Node (npm + tsc, no runtime dependencies): classes, numeric enums, item interfaces."""

from __future__ import annotations

from pltf.stubgen import banner, fill, model, readme, template
from pltf.stubgen.model import Field, Message, camel, doc_line, pascal, snake
from pltf.stubgen.renderer import Spelling, arguments, error_classes, methods, protocol, scripts, static

RESERVED = frozenset(
    (
        "break",
        "case",
        "catch",
        "class",
        "const",
        "continue",
        "debugger",
        "default",
        "delete",
        "do",
        "else",
        "enum",
        "export",
        "extends",
        "false",
        "finally",
        "for",
        "function",
        "if",
        "import",
        "in",
        "instanceof",
        "new",
        "null",
        "return",
        "super",
        "switch",
        "this",
        "throw",
        "true",
        "try",
        "typeof",
        "var",
        "void",
        "while",
        "with",
        "let",
        "static",
        "yield",
        "await",
        "implements",
        "interface",
        "package",
        "private",
        "protected",
        "public",
    )
)
CLIENT_NAMES = frozenset(("connect", "close", "send", "receive", "request"))
TS_TYPE = {
    "BYTE": "number",
    "BOOL": "boolean",
    "INT16": "number",
    "INT": "number",
    "DOUBLE": "number",
    "STRING": "string",
    "XML": "string",
}
HEAD = banner("// ")
SPELLING = Spelling(
    scalars=TS_TYPE,
    group="{item}[]",
    array="{base}[]",
    head='name: "{f.name}", prop: "{prop}", type: FieldType.{type}',
    type_name=pascal,
    wrap=("{ ", " }"),
    attrs={
        "repeat": "repeat: {f.repeat}",
        "const": "const: {f.const}",
        "min": "min: {f.min}",
        "max": "max: {f.max}",
        "allowed": "allowed: [{allowed}]",
        "group": "fields: {ITEM}_FIELDS, itemMin: {f.item_min}",
        "run": "run: {f.run}",
    },
    empty="[]",
    open="[",
    close="{indent}]",
    step="  ",
    member="  /** {doc} */\n  {name}: {type};",
    field_name=camel,
)
METHOD = (
    "  /** {m.name} (id {m.id}): {summary} */\n  {name}({params}): Promise<void> {{\n"
    "    return this.send({req});\n  }}\n",
    "  /** {m.name} (id {m.id}): {summary} */\n  {name}({params}): Promise<p.{reply}> {{\n"
    "    return this.request({req}, p.{reply});\n  }}\n",
)
# TypeScript versions pinned for reproducible builds (typescript has no dependencies of its own).
DEV_DEPENDENCIES = {"@types/node": "20.19.0", "typescript": "5.9.3"}


def param(name: str) -> str:
    p = camel(name)
    return p + "_" if p in RESERVED else p


def _errors() -> str:
    return error_classes(
        "/** {doc} */\nexport class {name} extends {base} {{\n  constructor(message: string) {{\n"
        '    super(message);\n    this.name = "{name}";\n  }}\n}}\n',
        "Error",
    )


def _default(f: Field) -> str:
    if f.is_group:
        return "[]"
    if f.enum:
        single = f"{f.enum}.{next(iter(model.enums()[f.enum].values))}"
    else:
        single = {"boolean": "false", "string": '""'}.get(TS_TYPE[f.type], "0")
    return "[" + ", ".join([single] * f.repeat) + "]" if f.repeat else single


def _telegram(m: Message) -> str:
    t = m.type_name
    direction = m.direction
    lines = [
        f"/** {m.doc} */",
        f"export class {t} extends Telegram {{",
        f"  static readonly ID = {m.id};",
        f'  static readonly NAME = "{m.name}";',
        f'  static readonly DIRECTION: Direction = "{direction}";',
    ]
    if m.opaque:
        lines += [
            "  static readonly LAYOUT: Layout = { opaque: true, fields: [] };",
            "  /** The bytes after the identifier (layout unknown). */",
            "  payload: Uint8Array = new Uint8Array(0);",
        ]
    else:
        table = SPELLING.table(m.fields, "  ")
        lines.append(f"  static readonly LAYOUT: Layout = {{ opaque: false, fields: {table} }};")
        lines += SPELLING.members(m.fields, "  /** {doc} */\n  {name}: {type} = {default};", _default)
    lines += [
        "",
        f"  constructor(init: Partial<{t}> = {{}}) {{",
        "    super();",
        "    Object.assign(this, init);",
        "  }",
        "}\n",
    ]
    return "\n".join(lines)


def _enum(name: str) -> str:
    values = [f"  {k} = {v}," for k, v in model.enums()[name].values.items()]
    return "\n".join([f"/** {model.enum_doc(name)} */\nexport enum {name} {{", *values, "}\n"])


def _item(name: str, fields: tuple[Field, ...]) -> str:
    return "\n".join(
        [
            f"/** One item of a repeated group. */\nexport interface {name} {{",
            *SPELLING.members(fields),
            "}\n",
            f"const {snake(name).upper()}_FIELDS: Field[] = {SPELLING.table(fields)};\n",
        ]
    )


def _registry(direction: str, telegrams: tuple[Message, ...]) -> str:
    const = "REQUESTS" if direction == "request" else "REPLIES"
    return "\n".join(
        [
            f"/** Every {direction} class, by identifier. */",
            f"export const {const}: ReadonlyMap<number, TelegramClass> = new Map<number, TelegramClass>([",
            *(f"  [{m.id}, {m.type_name}]," for m in telegrams),
            "]);\n",
        ]
    )


def _protocol() -> str:
    head = [
        HEAD,
        "/** Enums, group items and telegram classes of the PlatformCtrl protocol (guide 6.3, 6.4). */\n",
        'import { Direction, Field, FieldType, Layout, Telegram, TelegramClass } from "./wire";\n',
    ]
    return protocol(head, _enum, _item, _telegram, _registry)


def method_name(m: Message) -> str:
    return model.safe(camel(m.base), CLIENT_NAMES)


def _argument(f: Field) -> tuple[str, str]:
    prop, arg = camel(f.name), param(f.name)
    return f"{arg}: {SPELLING.type(f, 'p.')}", (prop if prop == arg else f"{prop}: {arg}")


def _method(m: Message) -> dict[str, str]:
    params, inits = arguments(m, ("payload: Uint8Array = new Uint8Array(0)", "payload"), _argument)
    return {
        "name": method_name(m),
        "params": ", ".join(params),
        "summary": doc_line(m.summary),
        "req": f"new p.{m.type_name}({{ {', '.join(inits)} }})" if inits else f"new p.{m.type_name}()",
    }


def _package() -> str:
    deps = ",\n".join(f'    "{k}": "{v}"' for k, v in DEV_DEPENDENCIES.items())
    note = banner("").strip().replace('"', "'")
    return (
        "{\n"
        f'  "name": "platformctrl",\n  "version": "0.1.0",\n  "private": true,\n'
        f'  "description": "PlatformCtrl socket protocol client. {note}",\n'
        '  "main": "dist/index.js",\n  "types": "dist/index.d.ts",\n'
        '  "scripts": {\n    "build": "tsc -p .",\n    "smoke": "node dist/smoke.js",\n'
        '    "vectors": "node dist/vectors.js"\n  },\n'
        f'  "devDependencies": {{\n{deps}\n  }}\n}}\n'
    )


README = readme(
    "typescript",
    "TypeScript (Node)",
    "`npm install` then `tsc`; typescript and @types/node are the only (dev) dependencies",
)


def render() -> dict[str, str]:
    return {
        "README.md": README,
        "package.json": _package(),
        "src/wire.ts": HEAD + fill(template("typescript", "wire.ts.tmpl"), ERRORS=_errors()),
        "src/protocol.ts": _protocol(),
        "src/client.ts": HEAD + fill(template("typescript", "client.ts.tmpl"), METHODS=methods(_method, METHOD)),
        **static(
            "typescript",
            HEAD,
            {
                "tsconfig.json": "tsconfig.json.tmpl",
                "src/index.ts": "index.ts.tmpl",
                "src/codec.ts": "codec.ts.tmpl",
                "src/smoke.ts": "smoke.ts.tmpl",
                "src/vectors.ts": "vectors.ts.tmpl",
                "src/waits.ts": "waits.ts.tmpl",
            },
        ),
        **scripts(
            "typescript",
            "npm install (typescript, @types/node; from the npm registry when not cached), then tsc.",
            "node dist/smoke.js",
            "node dist/vectors.js",
            "node_modules/\ndist/\npackage-lock.json\n",
        ),
    }
