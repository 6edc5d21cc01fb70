"""How the generated Python is laid out: docstrings wrapped at ``WIDTH``, one line when it fits, else one per item.

The generated modules follow the toolkit's formatting (ruff, line length 120), so they read like hand-written code.
"""

from __future__ import annotations

import textwrap
from collections.abc import Iterable

from pltf.stubgen.model import Field

WIDTH = 116  # docstring text; code lines may take the formatter's 120


def fits(line: str) -> bool:
    return len(line) <= WIDTH + 4


def one_or_many(one: str, many: list[str]) -> list[str]:
    """``one`` when it fits on a line, else the lines ``many``."""
    return [one] if fits(one) else many


def wrap(text: str, indent: str, hanging: str | None = None) -> list[str]:
    return textwrap.wrap(
        text,
        WIDTH,
        initial_indent=indent,
        subsequent_indent=hanging if hanging is not None else indent,
        break_long_words=False,
        break_on_hyphens=False,
    )


def docstring(indent: str, paragraphs: list[str], sections: list[tuple[str, list[tuple[str, str]]]]) -> list[str]:
    """A Google-style docstring: paragraphs, then sections of ``name: text`` entries."""
    body: list[str] = []
    for i, para in enumerate(paragraphs):
        if i:
            body.append("")
        body += wrap(para, indent)
    for title, entries in sections:
        if not entries:
            continue
        body += ["", f"{indent}{title}:"]
        for name, text in entries:
            body += wrap(f"{name}: {text}", indent + "    ", indent + "        ")
    body[0] = f'{indent}"""' + body[0][len(indent) :]
    if len(body) == 1 and len(body[0]) + 3 <= WIDTH + 4:
        return [body[0] + '"""']
    return [*body, f'{indent}"""']


def imports(module: str, names: Iterable[str]) -> list[str]:
    ordered = sorted(names)
    return one_or_many(
        f"from {module} import {', '.join(ordered)}", [f"from {module} import (", *[f"    {n}," for n in ordered], ")"]
    )


def all_names(names: Iterable[str]) -> list[str]:
    ordered = sorted(names)
    quoted = [f'"{n}"' for n in ordered]
    return one_or_many(f"__all__ = [{', '.join(quoted)}]", ["__all__ = [", *[f"    {q}," for q in quoted], "]"])


def unit_text(f: Field) -> str:
    parts = []
    if f.unit:
        parts.append(f"[{f.unit}]")
    if f.enum and f.enum != "Flag":
        parts.append(f"({f.enum})")
    if f.min is not None or f.max is not None:
        parts.append(f"(range {f.min if f.min is not None else ''}..{f.max if f.max is not None else ''})")
    return " ".join(parts)


def field_doc(f: Field) -> str:
    """A field's docstring entry: its description, values of an array, unit, enum and range."""
    text = f.description.rstrip(".")
    extra = unit_text(f)
    if f.repeat:
        text += f", {f.repeat} values"
    return f"{text} {extra}".rstrip() + "."
