"""Links from the documentation to files of the repository, checked at every build of the site.

An mkdocs hook (mkdocs.yml ``hooks:``). A page may link to any file of the repository by its path relative to
the page, as on a forge (``[the zoo](../zoo/README.md)`` from docs/x.md): mkdocs knows only docs/, so it would
warn, and ``--strict`` would fail. Here ``on_page_markdown`` checks that such a file exists, fails the build
(a warning under ``--strict``) when it does not or when a link leaves the repository, and marks the link;
``on_page_content`` points it from the built page to the file in the checkout (site/ is built inside it).

Rules: links inside docs/ are left to mkdocs' own validation (mkdocs.yml ``validation``); links with a scheme
(``https:``) are not touched here (docs/gen/linkcheck.py lists them); code blocks are never rewritten.
"""

from __future__ import annotations

import logging
import os
import re
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
MARK = "pltf-repo:"
LOG = logging.getLogger("mkdocs.plugins.pltf.repo_links")

LINK = re.compile(r"(\]\()([^)\s]+)(\))")
FENCE = re.compile(r"^(```|~~~)", re.M)
SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")
MARKED = re.compile(rf'href="{re.escape(MARK)}([^"#]*)(#[^"]*)?"')


def resolve(target: str, page_src: Path, docs_dir: Path) -> tuple[str, str | None]:
    """(what the link becomes, the problem or None) for one link target of the page at ``page_src``."""
    if SCHEME.match(target) or target.startswith(("#", "/")):
        return target, None
    path, _, fragment = target.partition("#")
    where = (page_src.parent / path).resolve()
    if where.is_relative_to(docs_dir.resolve()):
        return target, None
    if not where.is_relative_to(REPO):
        return target, f"links outside the repository: {target}"
    if not where.exists():
        return target, f"links to a file the repository does not have: {target}"
    rel = where.relative_to(REPO).as_posix()
    return f"{MARK}{rel}" + (f"#{fragment}" if fragment else ""), None


def _rewrite(text: str, page_src: Path, docs_dir: Path, where: str) -> str:
    def one(m: re.Match[str]) -> str:
        new, problem = resolve(m.group(2), page_src, docs_dir)
        if problem:
            LOG.warning("%s %s", where, problem)
        return m.group(1) + new + m.group(3)

    return LINK.sub(one, text)


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    docs_dir = Path(config["docs_dir"])
    src = docs_dir / page.file.src_uri
    out, inside = [], False
    for part in FENCE.split(markdown):  # the fence markers stay in the list, each toggles "inside a code block"
        if part in ("```", "~~~"):
            inside = not inside
            out.append(part)
        else:
            out.append(part if inside else _rewrite(part, src, docs_dir, f"Doc file '{page.file.src_uri}'"))
    return "".join(out)


def on_page_content(html: str, page: Any, config: Any, files: Any) -> str:
    here = Path(config["site_dir"]) / Path(page.file.dest_uri).parent

    def point(m: re.Match[str]) -> str:
        rel = os.path.relpath(REPO / m.group(1), here).replace(os.sep, "/")
        return f'href="{rel}{m.group(2) or ""}"'

    return MARKED.sub(point, html)
