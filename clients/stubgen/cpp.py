"""C++17 client: one header and two sources (standard library + POSIX sockets), g++ line or CMake."""

from __future__ import annotations

from pltf.stubgen import banner, fill, model, readme, template
from pltf.stubgen.model import Field, Message, doc_line, snake
from pltf.stubgen.renderer import Spelling, arguments, error_classes, methods, scripts, static

KEYWORDS = frozenset(
    (
        "alignas",
        "alignof",
        "and",
        "and_eq",
        "asm",
        "auto",
        "bitand",
        "bitor",
        "bool",
        "break",
        "case",
        "catch",
        "char",
        "class",
        "compl",
        "const",
        "constexpr",
        "const_cast",
        "continue",
        "decltype",
        "default",
        "delete",
        "do",
        "double",
        "dynamic_cast",
        "else",
        "enum",
        "explicit",
        "export",
        "extern",
        "false",
        "float",
        "for",
        "friend",
        "goto",
        "if",
        "inline",
        "int",
        "long",
        "mutable",
        "namespace",
        "new",
        "noexcept",
        "not",
        "not_eq",
        "nullptr",
        "operator",
        "or",
        "or_eq",
        "private",
        "protected",
        "public",
        "register",
        "reinterpret_cast",
        "return",
        "short",
        "signed",
        "sizeof",
        "static",
        "static_assert",
        "static_cast",
        "struct",
        "switch",
        "template",
        "this",
        "thread_local",
        "throw",
        "true",
        "try",
        "typedef",
        "typeid",
        "typename",
        "union",
        "unsigned",
        "using",
        "virtual",
        "void",
        "volatile",
        "wchar_t",
        "while",
        "xor",
        "xor_eq",
    )
)
CLIENT_NAMES = frozenset(("send", "receive", "request", "wait_target_reached", "wait_until"))
CPP_TYPE = {
    "BYTE": "uint8_t",
    "BOOL": "bool",
    "INT16": "int16_t",
    "INT": "int32_t",
    "DOUBLE": "double",
    "STRING": "std::string",
    "XML": "std::string",
}
HEAD = banner("// ")
# The per-telegram declarations and tables stay one field a line as generated, not as clang-format packs them (as
# the Rust client's per-telegram modules are #[rustfmt::skip]); runtime.cpp and the programs are clang-format clean.
UNFORMATTED = "// clang-format off\n"
DECLARATION = (
    "  /// {m.name} (id {m.id}): {summary}\n  void {name}({params});",
    "  /// {m.name} (id {m.id}): {summary}\n  {reply} {name}({params});",
)
DEFINITION = (
    "void Client::{name}({names}) {{\n  {m.type_name} r;\n{sets}  send(r);\n}}\n",
    "{reply} Client::{name}({names}) {{\n  {m.type_name} r;\n{sets}  return request<{reply}>(r);\n}}\n",
)


def member(name: str) -> str:
    return name + "_" if name in KEYWORDS else name


SPELLING = Spelling(
    scalars=CPP_TYPE,
    group="std::vector<{item}>",
    array="std::array<{base}, {repeat}>",
    head='Field("{f.name}", FieldType::{type})',
    type_name=model.pascal,
    sep="",
    attrs={
        "repeat": ".repeated({f.repeat})",
        "const": ".fixed({f.const})",
        "min": ".at_least({f.min})",
        "max": ".at_most({f.max})",
        "allowed": ".one_of({{{allowed}}})",
        "group": ".group({item_snake}_fields(), {f.item_min})",
        "run": ".run_of({f.run})",
    },
    empty="{}",
    open="{",
    close="\n{indent}}}",
    step="  ",
    trailing=False,
    member="  /// {doc}\n  {type} {name}{default};",
    field_name=member,
)


def _errors() -> str:
    return error_classes(
        "/// {doc}\nclass {name} : public {base} {{\n public:\n  using {base}::{base_name};\n"
        '  {virtual}const char* kind() const noexcept{override} {{ return "{name}"; }}\n}};\n',
        "std::runtime_error",
        virtual=("virtual ", ""),
        override=("", " override"),
    )


def _default(f: Field) -> str:
    if f.enum and not f.repeat:
        return f" = {f.enum}::{next(iter(model.enums()[f.enum].values))}"
    return "{}"


def _header_telegram(m: Message) -> str:
    t = m.type_name
    body = (
        ["  /// The bytes after the identifier (layout unknown).\n  std::string payload;"]
        if m.opaque
        else SPELLING.members(m.fields, default=_default)
    )
    direction = "Request" if m.direction == "request" else "Reply"
    return "\n".join(
        [
            f"/// {m.doc}",
            f"struct {t} final : Telegram {{",
            f"  static constexpr uint8_t ID = {m.id};",
            f'  static constexpr const char* NAME = "{m.name}";',
            "  static const Layout& layout();",
            "  static " + t + " from_values(const Values& v);",
            *body,
            "",
            "  uint8_t telegram_id() const override { return ID; }",
            "  const char* telegram_name() const override { return NAME; }",
            f"  Direction direction() const override {{ return Direction::{direction}; }}",
            "  const Layout& telegram_layout() const override { return layout(); }",
            "  Values to_values() const override;",
            "};\n",
        ]
    )


def _conversions(prefix: str, fields: tuple[Field, ...], obj: str) -> tuple[str, str]:
    user = [f for f in fields if f.user]
    to = ", ".join(f"detail::to_value({prefix}{member(f.name)})" for f in user)
    sets = "".join(f"  detail::from_value(v[{i}], {obj}.{member(f.name)});\n" for i, f in enumerate(user))
    return to, sets


def _header() -> str:
    enum_text = []
    for name, e in model.enums().items():
        values = "\n".join(f"  {k} = {v}," for k, v in e.values.items())
        cases = "\n".join(f'    case {name}::{k}: return "{k}";' for k in e.values)
        enum_text.append(
            f"/// {model.enum_doc(name)}\n"
            f"enum class {name} : int32_t {{\n{values}\n}};\n\n"
            f'/// The name of a {name} value ("?" for a value the spec does not list).\n'
            f"inline const char* to_string({name} v) {{\n  switch (v) {{\n{cases}\n  }}\n"
            f'  return "?";\n}}\n'
        )
    items = []
    for name, fields in model.item_types().items():
        body = "\n".join(SPELLING.members(fields, default=_default))
        items.append(f"/// One item of a repeated group.\nstruct {name} {{\n{body}\n}};\n")
    items.append("namespace detail {")
    for name in model.item_types():
        items.append(f"Value to_value(const {name}& item);\nvoid from_value(const Value& v, {name}& item);")
    items.append("}  // namespace detail")
    telegrams = [_header_telegram(m) for d in ("request", "reply") for m in model.messages(d)]
    return (
        HEAD
        + UNFORMATTED
        + fill(
            template("cpp", "platformctrl.hpp.tmpl"),
            ERRORS=_errors(),
            ENUMS="\n".join(enum_text).rstrip("\n"),
            ITEMS="\n".join(items),
            TELEGRAMS="\n".join(telegrams).rstrip("\n"),
            METHODS=methods(_method, DECLARATION),
        )
    )


def method_name(m: Message) -> str:
    return model.safe(snake(m.base), KEYWORDS | CLIENT_NAMES)


def _arguments(m: Message) -> tuple[list[str], list[str]]:
    def field(f: Field) -> tuple[str, str]:
        t, name = SPELLING.type(f), member(f.name)
        by_ref = f.is_group or f.is_text or f.repeat
        return (f"const {t}& {name}" if by_ref else f"{t} {name}"), name

    return arguments(m, ("const std::string& payload = {}", "payload"), field)


def _method(m: Message) -> dict[str, str]:
    params, args = _arguments(m)
    return {
        "name": method_name(m),
        "params": ", ".join(params),
        "summary": doc_line(m.summary),
        "names": ", ".join(p.split(" = ")[0] for p in params),
        "sets": "".join(f"  r.{a} = {a};\n" for a in args),
    }


def _protocol() -> str:
    out = [
        HEAD + UNFORMATTED,
        "// Field tables, value conversions, the telegram registry and the client's command methods.\n",
        '#include "platformctrl.hpp"\n',
        "namespace platformctrl {\n",
        "namespace {\n",
    ]
    for name, fields in model.item_types().items():
        out.append(f"std::vector<Field> {snake(name)}_fields() {{\n  return {SPELLING.table(fields, '  ')};\n}}\n")
    out.append(
        "template <class T>\nstd::unique_ptr<Telegram> make(const Values& v) {\n"
        "  return std::make_unique<T>(T::from_values(v));\n}\n\n}  // namespace\n\nnamespace detail {\n"
    )
    for name, fields in model.item_types().items():
        to, sets = _conversions("item.", fields, "item")
        out.append(
            f"Value to_value(const {name}& item) {{\n  return Value::of_list({{{to}}});\n}}\n\n"
            f"void from_value(const Value& value, {name}& item) {{\n  const Values& v = value.list;\n{sets}}}\n"
        )
    out.append("}  // namespace detail\n")
    for direction in ("request", "reply"):
        for m in model.messages(direction):
            t = m.type_name
            if m.opaque:
                layout, to, sets = "Layout{true, {}}", "Value::of_bytes(payload)", "  t.payload = v.at(0).bytes;\n"
            else:
                layout = f"Layout{{false, {SPELLING.table(m.fields, '    ')}}}"
                to, sets = _conversions("", m.fields, "t")
            unused = "" if sets else "  (void)v;\n"
            out.append(
                f"const Layout& {t}::layout() {{\n  static const Layout kLayout = {layout};\n"
                "  return kLayout;\n}\n\n"
                f"Values {t}::to_values() const {{\n  return {{{to}}};\n}}\n\n"
                f"{t} {t}::from_values(const Values& v) {{\n  {t} t;\n{unused}{sets}  return t;\n}}\n"
            )
    for func, ret, call in (
        ("layout_of", "const Layout*", "&{t}::layout()"),
        ("make_telegram", "std::unique_ptr<Telegram>", "make<{t}>(values)"),
    ):
        params = "uint8_t id, Direction direction" + (", const Values& values" if func == "make_telegram" else "")
        lines = [f"{ret} {func}({params}) {{", "  if (direction == Direction::Request) {", "    switch (id) {"]
        for direction in ("request", "reply"):
            if direction == "reply":
                lines += ["    }", "    return nullptr;", "  }", "  switch (id) {"]
            pad = "    " if direction == "request" else "  "
            lines += [f"{pad}  case {m.id}: return {call.format(t=m.type_name)};" for m in model.messages(direction)]
        lines += ["  }", "  return nullptr;", "}\n"]
        out.append("\n".join(lines))
    out.append(methods(_method, DEFINITION, lead="", end="\n"))
    out.append("}  // namespace platformctrl")
    return "\n".join(out) + "\n"


README = readme("cpp", "C++17", "plain `g++ -std=c++17`, or CMake")


def render() -> dict[str, str]:
    return {
        "README.md": README,
        "include/platformctrl.hpp": _header(),
        "src/protocol.cpp": _protocol(),
        **static(
            "cpp",
            HEAD,
            {
                "src/runtime.cpp": "runtime.cpp.tmpl",
                "examples/smoke.cpp": "smoke.cpp.tmpl",
                "examples/vectors.cpp": "vectors.cpp.tmpl",
            },
        ),
        **static("cpp", banner("# "), {"CMakeLists.txt": "CMakeLists.txt.tmpl"}),
        **scripts(
            "cpp",
            "compile with plain g++ (C++17) into build/ (or: cmake -S . -B build && cmake --build build).",
            "./build/smoke",
            "./build/vectors",
            "build/\n",
        ),
    }
