"""Python 3.10+ client: a package ``platformctrl`` (standard library only), dataclasses and IntEnums."""

from __future__ import annotations

import keyword

from pltf.stubgen import banner, fill, readme, template
from pltf.stubgen.model import Field, Message, doc_line, enum_doc, enums, field_doc, safe, snake
from pltf.stubgen.renderer import Spelling, arguments, error_classes, methods, protocol, scripts, static

KEYWORDS = frozenset(keyword.kwlist) | frozenset(("send", "receive", "request", "close"))
PY_TYPE = {
    "BYTE": "int",
    "BOOL": "bool",
    "INT16": "int",
    "INT": "int",
    "DOUBLE": "float",
    "STRING": "str",
    "XML": "str",
}
HEAD = banner("# ")
METHOD = (
    '    def {name}({params}) -> None:\n        """{docs}"""\n        self.send({call})\n',
    '    def {name}({params}) -> tg.{reply}:\n        """{docs}"""\n        return self.request({call}, tg.{reply})\n',
)
SPELLING = Spelling(
    scalars=PY_TYPE,
    group="tuple[{item}, ...]",
    array="tuple[{base}, ...]",
    head="{f.name!r}, {f.type}",
    wrap=("F(", ")"),
    attrs={
        "repeat": "repeat={f.repeat}",
        "const": "const={f.const}",
        "min": "min={f.min}",
        "max": "max={f.max}",
        "allowed": "allowed=frozenset({allowed_repr})",
        "group": "fields=_{item}_FIELDS, item_min={f.item_min}, convert={item}",
        "convert": "convert={convert}",
        "run": "run={f.run}",
    },
    empty="()",
    open="(",
    close="{indent})",
    step="    ",
    member='    {name}: {type}\n    """{doc}"""',
)


def _errors() -> str:
    return error_classes('class {name}({base}):\n    """{doc}"""\n\n', "Exception", end="\n\n")


def _telegram(m: Message) -> str:
    lines = [
        "@dataclass(frozen=True, slots=True)",
        f"class {m.type_name}(Telegram):",
        f'    """{m.name} {m.direction} (id {m.id}): {doc_line(m.summary)} [guide {doc_line(m.section)}]"""',
        "",
        f"    ID: ClassVar[int] = {m.id}",
        f'    NAME: ClassVar[str] = "{m.name}"',
        f'    DIRECTION: ClassVar[str] = "{m.direction}"',
    ]
    if m.opaque:
        lines += [
            "    OPAQUE: ClassVar[bool] = True",
            '    payload: bytes = b""',
            '    """The telegram\'s bytes after the identifier (layout unknown)."""',
        ]
    else:
        lines.append(f"    FIELDS: ClassVar[tuple[F, ...]] = {SPELLING.table(m.fields, '    ')}")
        assert not KEYWORDS & {f.name for f in m.user_fields}, f"{m.name}: a field named as a Python keyword"
        lines += SPELLING.members(m.fields)
    return "\n".join(lines) + "\n"


def _enum(name: str) -> str:
    values = [f"    {k} = {v}" for k, v in enums()[name].values.items()]
    return "\n".join([f'class {name}(enum.IntEnum):\n    """{enum_doc(name)}"""\n', *values, "\n"])


def _item(name: str, fields: tuple[Field, ...]) -> str:
    head = f'class {name}(NamedTuple):\n    """One item of a repeated group."""\n'
    return "\n".join([head, *SPELLING.members(fields), f"\n\n_{name}_FIELDS = {SPELLING.table(fields)}\n\n"])


def _registry(direction: str, telegrams: tuple[Message, ...]) -> str:
    body = "".join(f"    {m.id}: {m.type_name},\n" for m in telegrams)
    return f"{'REQUESTS' if direction == 'request' else 'REPLIES'}: dict[int, type[Telegram]] = {{\n{body}}}\n"


def _telegrams() -> str:
    head = [
        HEAD,
        '"""Enums, group items and telegram classes of the PlatformCtrl protocol (guide 6.3, 6.4)."""\n',
        "from __future__ import annotations\n",
        "import enum",
        "from dataclasses import dataclass",
        "from typing import ClassVar, NamedTuple\n",
        "from .wire import BOOL, BYTE, DOUBLE, GROUP, INT, INT16, STRING, XML, F, Telegram  # noqa: F401\n\n",
    ]
    return protocol(head, _enum, _item, lambda m: _telegram(m) + "\n", _registry)


def method_name(m: Message) -> str:
    return safe(snake(m.base), KEYWORDS)


def _method(m: Message) -> dict[str, str]:
    params, args = arguments(
        m, ('payload: bytes = b""', "payload"), lambda f: (f"{f.name}: {SPELLING.type(f, 'tg.')}", f.name)
    )
    doc = [f"{m.name} (id {m.id}): {doc_line(m.summary)} [guide {doc_line(m.section)}]"]
    doc += [f"{f.name}: {field_doc(f)}" for f in m.user_fields]
    docs = doc[0] if len(doc) == 1 else doc[0] + "\n\n" + "".join(f"        {d}\n" for d in doc[1:]) + "        "
    return {
        "name": method_name(m),
        "params": ", ".join(["self", *params]),
        "docs": docs,
        "call": f"tg.{m.type_name}({', '.join(args)})",
    }


README = readme("python", "Python 3.10+", "byte-compiles with `python3 -m compileall`")


def render() -> dict[str, str]:
    return {
        "README.md": README,
        "platformctrl/wire.py": HEAD + fill(template("python", "wire.py.tmpl"), ERRORS=_errors()),
        "platformctrl/telegrams.py": _telegrams(),
        "platformctrl/client.py": HEAD
        + fill(template("python", "client.py.tmpl"), METHODS=methods(_method, METHOD, lead="", end="\n")),
        **static(
            "python",
            HEAD,
            {
                "platformctrl/__init__.py": "__init__.py.tmpl",
                "platformctrl/codec.py": "codec.py.tmpl",
                "smoke.py": "smoke.py.tmpl",
                "run_vectors.py": "run_vectors.py.tmpl",
                "pyproject.toml": "pyproject.toml.tmpl",
            },
        ),
        **scripts(
            "python",
            "byte-compile the package and the two programs (python3, or $PYTHON).",
            '"${PYTHON:-python3}" smoke.py',
            '"${PYTHON:-python3}" run_vectors.py',
            "__pycache__/\nbuild/\n",
        ),
    }
