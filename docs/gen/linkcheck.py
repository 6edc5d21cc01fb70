"""Check every link of the built site: ``python docs/gen/linkcheck.py site`` (make docs runs it after mkdocs).

Exit status 0 when every relative link (``href`` and ``src`` of every page) reaches a file, in the site or in the
repository around it, and every ``#fragment`` into a page of the site names an element of that page; 1 with one
line per broken link otherwise; 2 when the folder is no built site. Links with a scheme (``https:``) are not
fetched: the network here is loopback only. They are counted, and listed with ``--external``.

Rules: a link to a folder means its index.html (mkdocs' directory URLs); a link from / starts at the site's
root (the 404 page's); the query string is ignored.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

ATTRS = {"href", "src"}


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.links: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if value is None:
                continue
            if name in ATTRS:
                self.links.append(value)
            elif name in ("id", "name"):
                self.ids.add(value)


@dataclass(frozen=True)
class Broken:
    page: Path
    link: str
    why: str


def _parse(path: Path, cache: dict[Path, _Page]) -> _Page:
    if path not in cache:
        page = _Page()
        page.feed(path.read_text(encoding="utf-8", errors="replace"))
        cache[path] = page
    return cache[path]


def _target(site: Path, page: Path, path: str) -> Path:
    base = site if path.startswith("/") else page.parent  # 404.html links from the site's root
    where = (base / unquote(path.lstrip("/"))).resolve() if path else page
    return where / "index.html" if where.is_dir() else where


def _anchored(fragment: str, target: Path, site: Path) -> bool:
    """Whether a fragment is checked: one into a page of the site (a repository file's are not)."""
    return bool(fragment) and target.suffix == ".html" and target.is_relative_to(site)


def check(site: Path) -> tuple[list[Broken], list[str]]:
    """(the broken links, the external ones) of every page under ``site``."""
    site = site.resolve()
    cache: dict[Path, _Page] = {}
    broken, external = [], []
    for page in sorted(site.rglob("*.html")):
        for link in _parse(page, cache).links:
            if link.startswith("//") or re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", link):
                external.append(link)
                continue
            parts = urlsplit(link)
            target = _target(site, page, parts.path)
            if not target.exists():
                broken.append(Broken(page, link, "no such file"))
            elif _anchored(parts.fragment, target, site) and unquote(parts.fragment) not in _parse(target, cache).ids:
                broken.append(Broken(page, link, f"{target.relative_to(site)} has no #{parts.fragment}"))
    return broken, external


def _lines(broken: list[Broken], site: Path) -> Iterator[str]:
    for b in broken:
        yield f"{b.page.relative_to(site.resolve())}: broken link {b.link!r}: {b.why}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="check every link of the built documentation site")
    parser.add_argument("site", type=Path, help="the built site (site/)")
    parser.add_argument("--external", action="store_true", help="list the links with a scheme (not fetched)")
    args = parser.parse_args(argv)
    if not (args.site / "index.html").is_file():
        print(f"linkcheck: error: {args.site} is no built site (no index.html): run make docs", file=sys.stderr)
        return 2
    broken, external = check(args.site)
    for line in _lines(broken, args.site):
        print(f"linkcheck: {line}", file=sys.stderr)
    if args.external:
        for link in sorted(set(external)):
            print(link)
    pages = sum(1 for _ in args.site.rglob("*.html"))
    print(f"linkcheck: {pages} pages, {len(broken)} broken links, {len(set(external))} external links not fetched")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
