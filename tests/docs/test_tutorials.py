"""Every page a user follows step by step runs as a test: its marked shell blocks (tests/docs/blocks.py), in order,
against the reference server or the emulator the page itself starts, so a tutorial cannot rot.

The default tier runs each page's quick blocks (about 25 s of CPU for all five pages); the slow tier runs every
block, the long ones too (the standard tier with motion, a zoo target that fails the suite, a fuzz campaign that
finds a planted bug and minimises it, its reproducer).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.docs.blocks import REPO, Block, PageRun, parse

DOCS = REPO / "docs"
PAGES = ["getting-started.md", *sorted(p.relative_to(DOCS).as_posix() for p in (DOCS / "tutorials").glob("*.md"))]


def _blocks(page: str) -> list[Block]:
    return parse((DOCS / page).read_text(encoding="utf-8"), page)


def _run(page: str, tmp_path: Path, *, slow: bool) -> None:
    run = PageRun(tmp_path)
    try:
        for block in _blocks(page):
            if slow or not block.slow:
                run.run(block)
    finally:
        run.close()


def test_every_tutorial_is_tested() -> None:
    assert len(PAGES) == 5, PAGES  # getting started and the four tutorials
    for page in PAGES:
        blocks = _blocks(page)
        assert any(not b.background and not b.file and not b.slow for b in blocks), f"{page}: no tested command"


@pytest.mark.parametrize("page", PAGES)
def test_tutorial(page: str, tmp_path: Path) -> None:
    _run(page, tmp_path, slow=False)


@pytest.mark.slow
@pytest.mark.parametrize("page", [p for p in PAGES if any(b.slow for b in _blocks(p))])
def test_tutorial_with_its_long_steps(page: str, tmp_path: Path) -> None:
    _run(page, tmp_path, slow=True)
