"""Python 3.10+ client: a package ``platformctrl`` (standard library only), dataclasses and IntEnums."""

from __future__ import annotations

import keyword

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
    snake,
)

KEYWORDS = frozenset(keyword.kwlist) | frozenset(("send", "receive", "request", "close"))
PY_TYPE = {"BYTE": "int", "BOOL": "bool", "INT16": "int", "INT": "int", "DOUBLE": "float", "STRING": "str",
           "XML": "str"}
HEAD = banner("# ")


def _errors() -> str:
    out = []
    for name, parent, doc in ERRORS:
        out.append(f"class {name}({parent or 'Exception'}):\n    \"\"\"{doc}\"\"\"\n\n")
    return "\n".join(out)


def _type(f: Field) -> str:
    if f.is_group:
        return f"tuple[{f.item}, ...]"
    base = f.enum or PY_TYPE[f.type]
    return f"tuple[{base}, ...]" if f.repeat else base


def _desc(f: Field) -> str:
    args = [repr(f.name), f.type]
    if f.repeat:
        args.append(f"repeat={f.repeat}")
    if f.const is not None:
        args.append(f"const={f.const}")
    if f.min is not None:
        args.append(f"min={f.min}")
    if f.max is not None:
        args.append(f"max={f.max}")
    if f.allowed is not None:
        args.append(f"allowed=frozenset({f.allowed!r})")
    if f.is_group:
        args.append(f"fields=_{f.item}_FIELDS, item_min={f.item_min}, convert={f.item}")
    elif f.enum:
        args.append(f"convert={f.enum}")
    elif f.type == "BOOL":
        args.append("convert=bool")
    if f.run:
        args.append(f"run={f.run}")
    return f"F({', '.join(args)})"


def _table(fields: tuple[Field, ...]) -> str:
    if not fields:
        return "()"
    return "(\n" + "".join(f"        {_desc(f)},\n" for f in fields) + "    )"


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
        lines += ["    OPAQUE: ClassVar[bool] = True", "    payload: bytes = b\"\"",
                  '    """The telegram\'s bytes after the identifier (layout unknown)."""']
    else:
        lines.append(f"    FIELDS: ClassVar[tuple[F, ...]] = {_table(m.fields)}")
        for f in m.user_fields:
            assert f.name not in KEYWORDS, f"{m.name}.{f.name}: a Python keyword"
            lines += [f"    {f.name}: {_type(f)}", f'    """{field_doc(f)}"""']
    return "\n".join(lines) + "\n"


def _telegrams() -> str:
    out = [HEAD, '"""Enums, group items and telegram classes of the PlatformCtrl protocol (guide 6.3, 6.4)."""\n',
           "from __future__ import annotations\n", "import enum", "from dataclasses import dataclass",
           "from typing import ClassVar, NamedTuple\n",
           "from .wire import BOOL, BYTE, DOUBLE, GROUP, INT, INT16, STRING, XML, F, Telegram  # noqa: F401\n\n"]
    for name, e in enums().items():
        out.append(f"class {name}(enum.IntEnum):\n    \"\"\"{doc_line(e.description)} [guide {e.section}]\"\"\"\n")
        out.extend(f"    {k} = {v}" for k, v in e.values.items())
        out.append("\n")
    for name, fields in item_types().items():
        out.append(f"class {name}(NamedTuple):\n    \"\"\"One item of a repeated group.\"\"\"\n")
        for f in fields:
            if f.user:
                out += [f"    {f.name}: {_type(f)}", f'    """{field_doc(f)}"""']
        out.append(f"\n\n_{name}_FIELDS = {_table(fields).replace(chr(10) + '    ', chr(10))}\n\n")
    for direction in ("request", "reply"):
        for m in messages(direction):
            out.append(_telegram(m) + "\n")
    for direction, const in (("request", "REQUESTS"), ("reply", "REPLIES")):
        body = "".join(f"    {m.id}: {m.type_name},\n" for m in messages(direction))
        out.append(f"{const}: dict[int, type[Telegram]] = {{\n{body}}}\n")
    return "\n".join(out)


def method_name(m: Message) -> str:
    return snake(m.base) + ("_" if snake(m.base) in KEYWORDS else "")


def _methods() -> str:
    out = []
    for c in commands():
        m = c.request
        params = ["self"]
        args = []
        doc = [f"{m.name} (id {m.id}): {doc_line(m.summary)} [guide {doc_line(m.section)}]"]
        if m.opaque:
            params.append('payload: bytes = b""')
            args.append("payload")
        for f in m.user_fields:
            params.append(f"{f.name}: {_ptype(f)}")
            args.append(f.name)
            doc.append(f"{f.name}: {field_doc(f)}")
        call = f"tg.{m.type_name}({', '.join(args)})"
        if c.reply is not None:
            ret, body = f"tg.{c.reply.type_name}", f"return self.request({call}, tg.{c.reply.type_name})"
        else:
            ret, body = "None", f"self.send({call})"
        docs = doc[0] if len(doc) == 1 else doc[0] + "\n\n" + "".join(f"        {d}\n" for d in doc[1:]) + "        "
        out.append(f"    def {method_name(m)}({', '.join(params)}) -> {ret}:\n"
                   f'        """{docs}"""\n        {body}\n')
    return "\n".join(out)


def _ptype(f: Field) -> str:
    named = f.item if f.is_group else f.enum
    return _type(f).replace(named, f"tg.{named}") if named else _type(f)


SMOKE_PY = '''"""Connect, initialize, print the position as one JSON line: python smoke.py HOST PORT."""

import json
import sys

from platformctrl import Client


def main() -> int:
    with Client(sys.argv[1], int(sys.argv[2])) as client:
        client.connect_to_pltf()
        client.init_pltf()
        pos = client.get_position()
    print(json.dumps({"x": pos.x, "y": pos.y, "angle": pos.angle}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
'''

VECTORS_PY = '''"""Vector runner: python run_vectors.py VECTORS.txt (the line format of clients/stubgen/vectors.py)."""

import sys

from platformctrl import ProtocolError, decode_frame, dump, encode


def check(line: str) -> str | None:
    parts = line.split(" ", 4)
    kind, direction, name, hexstr = parts[:4]
    data = b"" if hexstr == "-" else bytes.fromhex(hexstr)
    if kind == "E":
        try:
            t = decode_frame(data, direction)
        except ProtocolError as exc:
            got = type(exc).__name__
            return None if got == parts[4] else f"raised {got}, expected {parts[4]}"
        return f"decoded {t.NAME}, expected {parts[4]}"
    try:
        t = decode_frame(data, direction)
    except ProtocolError as exc:
        return f"{type(exc).__name__}: {exc}"
    want = parts[4] if len(parts) > 4 else ""
    if t.NAME != name:
        return f"decoded {t.NAME}"
    if dump(t) != want:
        return f"fields differ:\\n  got  {dump(t)}\\n  want {want}"
    if encode(t) != data:
        return f"re-encoded to {encode(t).hex()}"
    return None


def main() -> int:
    passed = failed = 0
    with open(sys.argv[1], encoding="ascii") as fh:
        for line in fh:
            line = line.rstrip("\\n")
            if not line or line.startswith("#"):
                continue
            problem = check(line)
            if problem is None:
                passed += 1
            else:
                failed += 1
                print(f"FAIL {' '.join(line.split(' ', 4)[:3])}: {problem}")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
'''

BUILD_SH = """#!/bin/sh
{banner}# sh build.sh: byte-compile the package and the two programs (python3, or $PYTHON).
set -e
cd "$(dirname "$0")"
"${{PYTHON:-python3}}" -m compileall -q platformctrl smoke.py run_vectors.py >/dev/null
"""
SMOKE_SH = """#!/bin/sh
{banner}# sh smoke.sh HOST PORT: build, then connect, init and print the position as one JSON line.
set -e
cd "$(dirname "$0")"
sh build.sh
exec "${{PYTHON:-python3}}" smoke.py "$1" "$2"
"""
VECTORS_SH = """#!/bin/sh
{banner}# sh vectors.sh FILE: build, then check every vector of FILE (python -m clients.stubgen.vectors writes it).
set -e
FILE="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
cd "$(dirname "$0")"
sh build.sh
exec "${{PYTHON:-python3}}" run_vectors.py "$FILE"
"""

INIT_PY = '''"""PlatformCtrl socket protocol client (generated): ``from platformctrl import Client``."""

from .client import Client
from .codec import TelegramDecoder, decode_data, decode_frame, encode
from .telegrams import *  # noqa: F403
from .wire import *  # noqa: F403
from .wire import dump

__all__ = ["Client", "TelegramDecoder", "decode_data", "decode_frame", "dump", "encode"]
'''

PYPROJECT = """{banner}[project]
name = "platformctrl"
version = "0.1.0"
description = "PlatformCtrl socket protocol client (generated, standard library only)"
requires-python = ">=3.10"

[build-system]
requires = ["setuptools>=68"]
build-backend = "setuptools.build_meta"

[tool.setuptools]
packages = ["platformctrl"]
"""


README = readme(
    title="Python 3.10+",
    build=(
        "byte-compiles with `python3 -m compileall`"
    ),
    snippet_lang="python",
    snippet="""
from platformctrl import Client, MotionMode

with Client("192.168.0.10", 10002) as client:
    client.connect_to_pltf()
    client.init_pltf()
    client.set_mode(MotionMode.MODE_MOTION_VEL)
    pos = client.get_position()  # GetPositionReply(x=..., y=..., angle=..., ...)
""",
    notes=(
        "Methods are the commands in snake_case; GET_* methods return the typed reply. `platformctrl.codec` "
        "is sans-IO: `encode`, `decode_frame`, `TelegramDecoder`."
    ),
)


def render() -> dict[str, str]:
    return {
        "README.md": README,
        "platformctrl/__init__.py": HEAD + INIT_PY,
        "platformctrl/wire.py": HEAD + fill(template("python", "wire.py.tmpl"), ERRORS=_errors()),
        "platformctrl/codec.py": HEAD + template("python", "codec.py.tmpl"),
        "platformctrl/telegrams.py": _telegrams(),
        "platformctrl/client.py": HEAD + fill(template("python", "client.py.tmpl"), METHODS=_methods()),
        "smoke.py": HEAD + SMOKE_PY,
        "run_vectors.py": HEAD + VECTORS_PY,
        "build.sh": BUILD_SH.format(banner=HEAD),
        "smoke.sh": SMOKE_SH.format(banner=HEAD),
        "vectors.sh": VECTORS_SH.format(banner=HEAD),
        "pyproject.toml": PYPROJECT.format(banner=HEAD),
        ".gitignore": HEAD + "__pycache__/\nbuild/\n",
    }
