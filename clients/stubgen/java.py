"""Java 17 client: package ``platformctrl`` (Maven layout, plain javac works), records and enums."""

from __future__ import annotations

import textwrap

from pltf.stubgen import banner, fill, model, readme, template
from pltf.stubgen.model import ERRORS, Field, Message, camel, doc_line, field_doc
from pltf.stubgen.renderer import BUILDER, Spelling, arguments, convert, methods, protocol, scripts, static

KEYWORDS = frozenset(
    (
        "abstract",
        "assert",
        "boolean",
        "break",
        "byte",
        "case",
        "catch",
        "char",
        "class",
        "const",
        "continue",
        "default",
        "do",
        "double",
        "else",
        "enum",
        "extends",
        "final",
        "finally",
        "float",
        "for",
        "goto",
        "if",
        "implements",
        "import",
        "instanceof",
        "int",
        "interface",
        "long",
        "native",
        "new",
        "package",
        "private",
        "protected",
        "public",
        "return",
        "short",
        "static",
        "strictfp",
        "super",
        "switch",
        "synchronized",
        "this",
        "throw",
        "throws",
        "transient",
        "try",
        "void",
        "volatile",
        "while",
        "true",
        "false",
        "null",
        "record",
        "var",
    )
)
CLIENT_NAMES = frozenset(("close", "send", "receive", "request"))
JAVA_TYPE = {
    "BYTE": "int",
    "BOOL": "boolean",
    "INT16": "short",
    "INT": "int",
    "DOUBLE": "double",
    "STRING": "String",
    "XML": "String",
}


def _banner() -> str:
    """The banner as google-java-format leaves it: within 100 columns, "do not edit" on the second line."""
    text = banner("").strip()
    cut = text.index("do not edit")
    return f"// {text[:cut].rstrip()}\n// {text[cut:]}\n"


HEAD = _banner()
SRC = "src/main/java/platformctrl/"
SPELLING = Spelling(
    scalars=JAVA_TYPE,
    group="List<{item}>",
    array="{base}[]",
    head='Field.of("{f.name}", FieldType.{f.type})',
    sep="",
    attrs={**BUILDER, "allowed": ".allowed({allowed})", "group": ".group({item}.FIELDS, {f.item_min})"},
    empty="List.of()",
    open="List.of(",
    close=")",
    step="    ",
    trailing=False,
)
METHOD = (
    "{doc}\n    public void {name}({params}) throws IOException {{\n        send({req});\n    }}\n",
    "{doc}\n    public {reply} {name}({params}) throws IOException {{\n"
    "        return request({req}, {reply}.class);\n    }}\n",
)
FORMAT_WIDTH = 100  # google-java-format's line width


def javadoc(text: str, indent: str = "    ") -> str:
    """``/** text */`` as google-java-format lays it out: on one line where it fits, else one sentence wrapped."""
    one = f"{indent}/** {text} */"
    if len(one) <= FORMAT_WIDTH:
        return one
    lines = textwrap.wrap(text, FORMAT_WIDTH - len(indent) - 3, break_long_words=False, break_on_hyphens=False)
    return "\n".join([f"{indent}/**", *(f"{indent} * {line}" for line in lines), f"{indent} */"])


# Values cross the runtime as Object: Long, Double, String, byte[], List<Object> (arrays, group items).
TO_VALUE = {
    "group": "Wire.group({n}, {item}::toValues)",
    "enum_array": "Wire.enums({n}, e -> e.value)",
    "array": "Wire.list({n})",
    "enum": "(long) {n}.value",
    "BOOL": "Wire.bool({n})",
    "DOUBLE": "{n}",
    "text": "{n}",
    "int": "(long) {n}",
}
FROM_VALUE = {
    "group": "Wire.items({v}, {item}::fromValues)",
    "enum_array": "Wire.enumArray({v}, {enum}::of, {enum}[]::new)",
    "array_INT16": "Wire.shorts({v})",
    "array": "Wire.ints({v})",
    "enum": "{enum}.of(Wire.num({v}))",
    "BYTE": "Wire.u8({v})",
    "BOOL": "Wire.bool({v})",
    "INT16": "Wire.i16({v})",
    "INT": "Wire.i32({v})",
    "DOUBLE": "(Double) {v}",
    "text": "(String) {v}",
}


def name(field: str) -> str:
    n = camel(field)
    return n + "_" if n in KEYWORDS else n


def _errors() -> str:
    out = [
        HEAD,
        "package platformctrl;\n",
        "import java.io.IOException;\n",
        "/**",
        " * Base of every codec error (spec/errors.py ProtocolError); the nested classes are the error",
        " * family, {@link #kind()} their class name. Local errors: we tried to encode something the protocol",
        " * forbids; remote errors: the peer sent bytes the protocol forbids.",
        " */",
        "public class ProtocolException extends IOException {",
        "    private static final long serialVersionUID = 1L;",
        "",
        "    public ProtocolException(String message) {",
        "        super(message);",
        "    }",
        "",
        "    /** The class name in the error family, e.g. Truncated. */",
        "    public String kind() {",
        "        return getClass().getSimpleName();",
        "    }",
    ]
    for err, parent, doc in ERRORS[1:]:
        base = "ProtocolException" if parent == "ProtocolError" else parent
        out += [
            "",
            f"    /** {doc} */",
            f"    public static class {err} extends {base} {{",
            "        private static final long serialVersionUID = 1L;",
            "",
            f"        public {err}(String message) {{",
            "            super(message);",
            "        }",
            "    }",
        ]
    return "\n".join([*out, "}"]) + "\n"


def _record(kind: str, rname: str, doc: str, fields: tuple[Field, ...], implements: str, body: list[str]) -> str:
    user = [f for f in fields if f.user]
    comps = ", ".join(f"{SPELLING.type(f)} {name(f.name)}" for f in user)
    params = "".join(f"\n     * @param {name(f.name)} {field_doc(f)}" for f in user)
    lines = [f"    /**\n     * {doc}{params}\n     */", f"    public record {rname}({comps}){implements} {{"]
    lines += body
    to = ", ".join(convert(TO_VALUE, f, n=name(f.name)) for f in user)
    frm = ", ".join(convert(FROM_VALUE, f, v=f"v.get({i})") for i, f in enumerate(user))
    lines += [
        f"        {kind} List<Object> toValues() {{",
        f"            return Arrays.asList({to});",
        "        }",
        "",
        f"        static {rname} fromValues(List<Object> v) {{",
        f"            return new {rname}({frm});",
        "        }",
        "    }\n",
    ]
    return "\n".join(lines)


def _telegram(m: Message) -> str:
    t = m.type_name
    doc = m.doc
    head = [
        f"        public static final int ID = {m.id};",
        f"        public static final Layout LAYOUT = new Layout({str(m.opaque).lower()}, "
        f"{SPELLING.table(m.fields, '            ')});",
        "",
        "        @Override public int telegramId() { return ID; }",
        f'        @Override public String telegramName() {{ return "{m.name}"; }}',
        "        @Override public Layout telegramLayout() { return LAYOUT; }",
        "",
    ]
    if m.opaque:
        return "\n".join(
            [
                f"    /**\n     * {doc}\n"
                "     * @param payload the bytes after the identifier (layout unknown)\n     */",
                f"    public record {t}(byte[] payload) implements Telegram {{",
                *head,
                "        @Override public List<Object> toValues() { return List.of(payload); }",
                "",
                f"        static {t} fromValues(List<Object> v) {{ return new {t}((byte[]) v.get(0)); }}",
                "    }\n",
            ]
        )
    return _record("@Override public", t, doc, m.fields, " implements Telegram", head)


def _enum(ename: str) -> str:
    values = ",\n".join(f"        /** {k} = {v} */\n        {k}({v})" for k, v in model.enums()[ename].values.items())
    return (
        f"    /** {model.enum_doc(ename)} */\n"
        f"    public enum {ename} {{\n{values};\n\n        public final int value;\n\n"
        f"        {ename}(int value) {{\n            this.value = value;\n        }}\n\n"
        f"        /** The constant with this value (the decoder checked that there is one). */\n"
        f"        public static {ename} of(long value) {{\n"
        f"            for ({ename} e : values()) {{\n                if (e.value == value) {{\n"
        f"                    return e;\n                }}\n            }}\n"
        f'            throw new IllegalArgumentException("no {ename} " + value);\n        }}\n    }}\n'
    )


def _item(iname: str, fields: tuple[Field, ...]) -> str:
    body = [f"        static final List<Field> FIELDS = {SPELLING.table(fields, '            ')};", ""]
    return _record("public", iname, "One item of a repeated group.", fields, "", body)


def _registry(direction: str, telegrams: tuple[Message, ...]) -> str:
    entries = ",\n".join(
        f"        Map.entry({m.id}, new Entry({m.type_name}.LAYOUT, {m.type_name}::fromValues))" for m in telegrams
    )
    const = "REQUESTS" if direction == "request" else "REPLIES"
    return (
        f"    /** Every {direction} telegram, by identifier. */\n"
        f"    static final Map<Integer, Entry> {const} = Map.ofEntries(\n{entries});\n"
    )


def _protocol() -> str:
    head = [
        HEAD,
        "package platformctrl;\n",
        "import java.util.Arrays;",
        "import java.util.List;",
        "import java.util.Map;\n",
        "import platformctrl.Wire.Entry;",
        "import platformctrl.Wire.Field;",
        "import platformctrl.Wire.FieldType;",
        "import platformctrl.Wire.Layout;\n",
        "/** Enums, group items and telegram records of the PlatformCtrl protocol (guide 6.3, 6.4). */",
        "public final class Protocol {",
        "    private Protocol() {}\n",
    ]
    return protocol(head, _enum, _item, _telegram, _registry, end="\n}\n")


def method_name(m: Message) -> str:
    return model.safe(camel(m.base), KEYWORDS | CLIENT_NAMES)


def _method(m: Message) -> dict[str, str]:
    params, args = arguments(
        m, ("byte[] payload", "payload"), lambda f: (f"{SPELLING.type(f)} {name(f.name)}", name(f.name))
    )
    return {
        "name": method_name(m),
        "params": ", ".join(params),
        "req": f"new {m.type_name}({', '.join(args)})",
        "doc": javadoc(f"{m.name} (id {m.id}): {doc_line(m.summary)}"),
    }


README = readme("java", "Java 17", "plain `javac`; `mvn package` works too")


def render() -> dict[str, str]:
    statics = ("Wire", "Telegram", "TelegramDecoder", "Smoke", "VectorRunner")
    return {
        "README.md": README,
        "pom.xml": fill(template("java", "pom.xml.tmpl"), TEXT=banner("").strip()),
        SRC + "ProtocolException.java": _errors(),
        SRC + "Protocol.java": _protocol(),
        SRC + "Client.java": HEAD + fill(template("java", "Client.java.tmpl"), METHODS=methods(_method, METHOD)),
        **static("java", HEAD, {f"{SRC}{name}.java": f"{name}.java.tmpl" for name in statics}),
        **scripts(
            "java",
            "compile with plain javac into build/classes (Java 17; `mvn package` works too).",
            "java -cp build/classes platformctrl.Smoke",
            "java -cp build/classes platformctrl.VectorRunner",
            "build/\ntarget/\n",
        ),
    }
