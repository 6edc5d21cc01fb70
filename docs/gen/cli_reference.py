"""The CLI reference page, generated from pltf's own argument parser at every build of the site.

An mkdocs hook (mkdocs.yml ``hooks:``): ``on_files`` adds ``reference/cli.md`` to the site, rendered from
``pltf.cli.main.make_parser`` with every command loaded, so the page cannot fall behind the parser: an option
added to a command is on the page at the next ``make docs``. ``on_page_markdown`` puts one command's part (usage,
options, exit statuses) where a tool's page has the line ``<!-- pltf-cli NAME -->``; an unknown NAME fails the
build. ``python docs/gen/cli_reference.py`` prints the page.

Rules:
- Everything on the page comes from the parser: the command's help, its usage line, one table per option group
  (option, value, default, meaning) and the exit statuses of its epilog (``pltf.cli.options.exit_status``).
- The usage is wrapped at a fixed width, so the page is the same on every terminal.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import logging
import os
import re
import sys
from collections.abc import Iterator
from typing import Any

PAGE = "reference/cli.md"
INSERT = re.compile(r"^<!-- pltf-cli (\S+) -->$", re.M)
LOG = logging.getLogger("mkdocs.plugins.pltf.cli_reference")
WIDTH = "100"

HEAD = """# CLI reference

Generated from the parser of `pltf` at every build of this site (`docs/gen/cli_reference.py`): what is here is
what `pltf COMMAND --help` prints. Every command reports a problem as one line on stderr,
`pltf COMMAND: error: ...`, never a traceback; `--target` is always `HOST:PORT` (`[::1]:10000` for IPv6).
"""


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def _default(action: argparse.Action) -> str:
    if action.nargs == 0 or action.default in (None, argparse.SUPPRESS, False, [], ()):
        return ""
    return f"`{action.default}`"


def _value(action: argparse.Action) -> str:
    if action.nargs == 0:
        return ""
    if action.choices is not None:
        return " \\| ".join(f"`{c}`" for c in action.choices)
    return f"`{action.metavar or action.dest.upper()}`"


def _help(action: argparse.Action) -> str:
    text = (action.help or "").replace("%(default)s", str(action.default))
    return _cell(text)


def _group_table(group: argparse._ArgumentGroup) -> list[str]:
    actions = [a for a in group._group_actions if a.help != argparse.SUPPRESS and a.dest != "help"]
    if not actions:
        return []
    title = (group.title or "options").removesuffix(":")
    rows = [f"**{title}**", "", "| option | value | default | meaning |", "|---|---|---|---|"]
    for a in actions:
        flags = ", ".join(f"`{f}`" for f in a.option_strings) or f"`{a.dest}` (positional)"
        rows.append(f"| {flags} | {_value(a)} | {_default(a)} | {_help(a)} |")
    return [*rows, ""]


def _exit_table(epilog: str | None) -> list[str]:
    statuses = re.findall(r"^\s+(\d+)\s+(.+)$", (epilog or "").partition("exit status:")[2], flags=re.M)
    if not statuses:
        return []
    rows = ["**exit status**", "", "| status | meaning |", "|---|---|"]
    return [*rows, *(f"| {code} | {_cell(text)} |" for code, text in statuses), ""]


@contextlib.contextmanager
def _fixed_width() -> Iterator[None]:
    """argparse wraps the usage at the terminal's width (COLUMNS): a fixed one while formatting, then the old."""
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = WIDTH
    try:
        yield
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


def _body(parser: argparse.ArgumentParser, help_text: str) -> list[str]:
    with _fixed_width():
        usage = parser.format_usage().rstrip()
    out = [_cell(help_text), "", "```text", usage, "```", ""]
    if parser.description and parser.description != help_text:
        out += [_cell(parser.description), ""]
    for group in parser._action_groups:
        out += _group_table(group)
    return out + _exit_table(parser.epilog)


@functools.cache
def _parsers() -> dict[str, tuple[argparse.ArgumentParser, str]]:
    """Command name -> (its parser, its one-line help), every command loaded."""
    from pltf.cli.main import COMMANDS, make_parser

    parser = make_parser(load=COMMANDS)
    return {name: (parser.commands[name], help_text) for name, (_, help_text) in COMMANDS.items()}


def render() -> str:
    out = [HEAD]
    out += [f"- [`pltf {name}`](#pltf-{name}): {_cell(help_text)}" for name, (_, help_text) in _parsers().items()]
    out.append("")
    for name, (parser, help_text) in _parsers().items():
        out += [f"## pltf {name}", "", *_body(parser, help_text)]
    return "\n".join(out).rstrip() + "\n"


def section(name: str) -> str:
    """One command's usage, options and exit statuses, for a tool's page. KeyError for an unknown command."""
    parser, help_text = _parsers()[name]
    return "\n".join(_body(parser, help_text)).rstrip() + "\n"


def on_files(files: Any, config: Any) -> Any:
    """mkdocs hook: the page joins the site's files (generated in memory, never written into docs/)."""
    from mkdocs.structure.files import File

    files.append(File.generated(config, PAGE, content=render()))
    return files


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    """mkdocs hook: ``<!-- pltf-cli NAME -->`` on a line of its own becomes that command's part of the reference."""

    def one(m: re.Match[str]) -> str:
        if m.group(1) not in _parsers():
            LOG.warning("Doc file '%s': <!-- pltf-cli %s -->: pltf has no such command", page.file.src_uri, m.group(1))
            return m.group(0)
        return section(m.group(1))

    return INSERT.sub(one, markdown)


if __name__ == "__main__":
    sys.stdout.write(render())
