"""Java 17 client: package ``platformctrl`` (Maven layout, plain javac works), records and enums."""

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
)

KEYWORDS = frozenset((
    "abstract", "assert", "boolean", "break", "byte", "case", "catch", "char", "class", "const", "continue",
    "default", "do", "double", "else", "enum", "extends", "final", "finally", "float", "for", "goto", "if",
    "implements", "import", "instanceof", "int", "interface", "long", "native", "new", "package", "private",
    "protected", "public", "return", "short", "static", "strictfp", "super", "switch", "synchronized", "this",
    "throw", "throws", "transient", "try", "void", "volatile", "while", "true", "false", "null", "record", "var",
))
CLIENT_NAMES = frozenset(("close", "send", "receive", "request"))
JAVA_TYPE = {"BYTE": "int", "BOOL": "boolean", "INT16": "short", "INT": "int", "DOUBLE": "double",
             "STRING": "String", "XML": "String"}
HEAD = banner("// ")
SRC = "src/main/java/platformctrl/"


def name(field: str) -> str:
    n = camel(field)
    return n + "_" if n in KEYWORDS else n


def _errors() -> str:
    out = [HEAD, "package platformctrl;\n", "import java.io.IOException;\n",
           "/**", " * Base of every codec error (spec/errors.py ProtocolError); the nested classes are the error",
           " * family, {@link #kind()} their class name. Local errors: we tried to encode something the protocol",
           " * forbids; remote errors: the peer sent bytes the protocol forbids.", " */",
           "public class ProtocolException extends IOException {",
           "    private static final long serialVersionUID = 1L;", "",
           "    public ProtocolException(String message) {", "        super(message);", "    }", "",
           "    /** The class name in the error family, e.g. Truncated. */",
           "    public String kind() {", "        return getClass().getSimpleName();", "    }"]
    for err, parent, doc in ERRORS[1:]:
        base = "ProtocolException" if parent == "ProtocolError" else parent
        out += ["", f"    /** {doc} */", f"    public static class {err} extends {base} {{",
                "        private static final long serialVersionUID = 1L;", "",
                f"        public {err}(String message) {{", "            super(message);", "        }", "    }"]
    return "\n".join([*out, "}"]) + "\n"


def _type(f: Field) -> str:
    if f.is_group:
        return f"List<{f.item}>"
    base = f.enum or JAVA_TYPE[f.type]
    return f"{base}[]" if f.repeat else base


def _to_value(f: Field) -> str:
    n = name(f.name)
    if f.is_group:
        return f"Wire.group({n}, {f.item}::toValues)"
    if f.repeat:
        return f"Wire.enums({n}, e -> e.value)" if f.enum else f"Wire.list({n})"
    if f.enum:
        return f"(long) {n}.value"
    if f.type == "BOOL":
        return f"Wire.bool({n})"
    if f.type in ("DOUBLE", "STRING", "XML"):
        return n
    return f"(long) {n}"


def _from_value(f: Field, v: str) -> str:
    if f.is_group:
        return f"Wire.items({v}, {f.item}::fromValues)"
    if f.repeat:
        if f.enum:
            return f"Wire.enumArray({v}, {f.enum}::of, {f.enum}[]::new)"
        return f"Wire.shorts({v})" if f.type == "INT16" else f"Wire.ints({v})"
    if f.enum:
        return f"{f.enum}.of(Wire.num({v}))"
    return {"BYTE": "Wire.u8({})", "BOOL": "Wire.bool({})", "INT16": "Wire.i16({})", "INT": "Wire.i32({})",
            "DOUBLE": "(Double) {}", "STRING": "(String) {}", "XML": "(String) {}"}[f.type].format(v)


def _desc(f: Field) -> str:
    out = f'Field.of("{f.name}", FieldType.{f.type})'
    if f.repeat:
        out += f".repeat({f.repeat})"
    if f.const is not None:
        out += f".constant({f.const})"
    if f.min is not None:
        out += f".min({f.min})"
    if f.max is not None:
        out += f".max({f.max})"
    if f.allowed is not None:
        out += f".allowed({', '.join(map(str, f.allowed))})"
    if f.is_group:
        out += f".group({f.item}.FIELDS, {f.item_min})"
    if f.run:
        out += f".run({f.run})"
    return out


def _table(fields: tuple[Field, ...], indent: str) -> str:
    if not fields:
        return "List.of()"
    return "List.of(\n" + ",\n".join(f"{indent}    {_desc(f)}" for f in fields) + ")"


def _record(kind: str, rname: str, doc: str, fields: tuple[Field, ...], implements: str, body: list[str]) -> str:
    user = [f for f in fields if f.user]
    comps = ", ".join(f"{_type(f)} {name(f.name)}" for f in user)
    params = "".join(f"\n     * @param {name(f.name)} {field_doc(f)}" for f in user)
    lines = [f"    /**\n     * {doc}{params}\n     */", f"    public record {rname}({comps}){implements} {{"]
    lines += body
    to = ", ".join(_to_value(f) for f in user)
    frm = ", ".join(_from_value(f, f"v.get({i})") for i, f in enumerate(user))
    lines += [f"        {kind} List<Object> toValues() {{", f"            return Arrays.asList({to});", "        }", "",
              f"        static {rname} fromValues(List<Object> v) {{", f"            return new {rname}({frm});",
              "        }", "    }\n"]
    return "\n".join(lines)


def _telegram(m: Message) -> str:
    t = m.type_name
    doc = f"{m.name} ({m.direction}, id {m.id}): {doc_line(m.summary)} [guide {doc_line(m.section)}]"
    head = [f"        public static final int ID = {m.id};",
            f"        public static final Layout LAYOUT = new Layout({str(m.opaque).lower()}, "
            f"{_table(m.fields, '            ')});", "",
            "        @Override public int telegramId() { return ID; }",
            f'        @Override public String telegramName() {{ return "{m.name}"; }}',
            "        @Override public Layout telegramLayout() { return LAYOUT; }", ""]
    if m.opaque:
        return "\n".join([f"    /**\n     * {doc}\n"
                          "     * @param payload the bytes after the identifier (layout unknown)\n     */",
                          f"    public record {t}(byte[] payload) implements Telegram {{", *head,
                          "        @Override public List<Object> toValues() { return List.of(payload); }", "",
                          f"        static {t} fromValues(List<Object> v) {{ return new {t}((byte[]) v.get(0)); }}",
                          "    }\n"])
    return _record("@Override public", t, doc, m.fields, " implements Telegram", head)


def _protocol() -> str:
    out = [HEAD, "package platformctrl;\n", "import java.util.Arrays;", "import java.util.List;",
           "import java.util.Map;\n", "import platformctrl.Wire.Entry;", "import platformctrl.Wire.Field;",
           "import platformctrl.Wire.FieldType;", "import platformctrl.Wire.Layout;\n",
           "/** Enums, group items and telegram records of the PlatformCtrl protocol (guide 6.3, 6.4). */",
           "public final class Protocol {", "    private Protocol() {}\n"]
    for ename, e in enums().items():
        values = ",\n".join(f"        /** {k} = {v} */\n        {k}({v})" for k, v in e.values.items())
        out.append(f"    /** {doc_line(e.description)} [guide {doc_line(e.section)}] */\n"
                   f"    public enum {ename} {{\n{values};\n\n        public final int value;\n\n"
                   f"        {ename}(int value) {{\n            this.value = value;\n        }}\n\n"
                   f"        /** The constant with this value (the decoder checked that there is one). */\n"
                   f"        public static {ename} of(long value) {{\n"
                   f"            for ({ename} e : values()) {{\n                if (e.value == value) {{\n"
                   f"                    return e;\n                }}\n            }}\n"
                   f'            throw new IllegalArgumentException("no {ename} " + value);\n        }}\n    }}\n')
    for iname, fields in item_types().items():
        body = [f"        static final List<Field> FIELDS = {_table(fields, '            ')};", ""]
        out.append(_record("public", iname, "One item of a repeated group.", fields, "", body))
    for direction in ("request", "reply"):
        for m in messages(direction):
            out.append(_telegram(m))
    for direction, const in (("request", "REQUESTS"), ("reply", "REPLIES")):
        entries = ",\n".join(f"        Map.entry({m.id}, new Entry({m.type_name}.LAYOUT, {m.type_name}::fromValues))"
                             for m in messages(direction))
        out.append(f"    /** Every {direction} telegram, by identifier. */\n"
                   f"    static final Map<Integer, Entry> {const} = Map.ofEntries(\n{entries});\n")
    return "\n".join(out).rstrip("\n") + "\n}\n"


def method_name(m: Message) -> str:
    n = camel(m.base)
    return n + "_" if n in KEYWORDS or n in CLIENT_NAMES else n


def _methods() -> str:
    out = []
    for c in commands():
        m = c.request
        params, args = [], []
        if m.opaque:
            params.append("byte[] payload")
            args.append("payload")
        for f in m.user_fields:
            params.append(f"{_type(f)} {name(f.name)}")
            args.append(name(f.name))
        req = f"new {m.type_name}({', '.join(args)})"
        doc = f"    /** {m.name} (id {m.id}): {doc_line(m.summary)} */"
        sig = f"{method_name(m)}({', '.join(params)}) throws IOException"
        if c.reply is None:
            out.append(f"{doc}\n    public void {sig} {{\n        send({req});\n    }}\n")
        else:
            r = c.reply.type_name
            out.append(f"{doc}\n    public {r} {sig} {{\n        return request({req}, {r}.class);\n    }}\n")
    return "\n" + "\n".join(out).rstrip("\n")


POM = """<?xml version="1.0" encoding="UTF-8"?>
<!-- {text} -->
<project xmlns="http://maven.apache.org/POM/4.0.0" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
         xsi:schemaLocation="http://maven.apache.org/POM/4.0.0 https://maven.apache.org/xsd/maven-4.0.0.xsd">
  <modelVersion>4.0.0</modelVersion>
  <groupId>platformctrl</groupId>
  <artifactId>platformctrl</artifactId>
  <version>0.1.0</version>
  <packaging>jar</packaging>
  <description>PlatformCtrl socket protocol client (generated, standard library only)</description>
  <properties>
    <maven.compiler.release>17</maven.compiler.release>
    <project.build.sourceEncoding>UTF-8</project.build.sourceEncoding>
  </properties>
  <build>
    <plugins>
      <plugin>
        <groupId>org.apache.maven.plugins</groupId>
        <artifactId>maven-compiler-plugin</artifactId>
        <version>3.13.0</version>
      </plugin>
    </plugins>
  </build>
</project>
"""
BUILD_SH = """#!/bin/sh
{banner}# sh build.sh: compile with plain javac into build/classes (Java 17; `mvn package` works too).
set -e
cd "$(dirname "$0")"
if [ ! -f build/classes/.stamp ] || [ -n "$(find src -newer build/classes/.stamp -name '*.java')" ]; then
  rm -rf build/classes
  mkdir -p build/classes
  javac --release 17 -encoding UTF-8 -d build/classes $(find src/main/java -name '*.java')
  touch build/classes/.stamp
fi
"""
SMOKE_SH = """#!/bin/sh
{banner}# sh smoke.sh HOST PORT: build, then connect, init and print the position as one JSON line.
set -e
cd "$(dirname "$0")"
sh build.sh
exec java -cp build/classes platformctrl.Smoke "$1" "$2"
"""
VECTORS_SH = """#!/bin/sh
{banner}# sh vectors.sh FILE: build, then check every vector of FILE (python -m clients.stubgen.vectors writes it).
set -e
FILE="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
cd "$(dirname "$0")"
sh build.sh
exec java -cp build/classes platformctrl.VectorRunner "$FILE"
"""


README = readme(
    title="Java 17",
    build=(
        "plain `javac`; `mvn package` works too"
    ),
    snippet_lang="java",
    snippet="""
try (Client client = new Client("192.168.0.10", 10002, 10000)) {
    client.connectToPltf();
    client.setMode(Protocol.MotionMode.MODE_MOTION_VEL);
    Protocol.GetPositionReply pos = client.getPosition();
}
""",
    notes=(
        "Telegrams and group items are records nested in `Protocol`; errors are `ProtocolException` "
        "subclasses (`ProtocolException.Truncated`, ...), checked as they extend IOException."
    ),
)


def render() -> dict[str, str]:
    sh = HEAD.replace("// ", "# ")
    files = {
        "README.md": README,
        "pom.xml": POM.format(text=banner("").strip()),
        SRC + "ProtocolException.java": _errors(),
        SRC + "Protocol.java": _protocol(),
        SRC + "Client.java": HEAD + fill(template("java", "Client.java.tmpl"), METHODS=_methods()),
        "build.sh": BUILD_SH.format(banner=sh),
        "smoke.sh": SMOKE_SH.format(banner=sh),
        "vectors.sh": VECTORS_SH.format(banner=sh),
        ".gitignore": sh + "build/\ntarget/\n",
    }
    for static in ("Wire", "Telegram", "TelegramDecoder", "Smoke", "VectorRunner"):
        files[SRC + f"{static}.java"] = HEAD + template("java", f"{static}.java.tmpl")
    return files

