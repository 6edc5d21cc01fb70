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

CHROMIUM = Path("/usr/bin/chromium")
PATIENCE_MS = 60_000  # a guard against a hang on a loaded machine, not a speed assertion

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


@pytest.mark.slow
def test_the_gui_tutorial_steps_in_a_browser(tmp_path: Path) -> None:
    """Section 2 of the GUI tutorial as a person does it, in Debian's chromium: Init, mode Automatic, Start, each
    control found by the name the page gives it; what the platform did is read over its other port."""
    sync_api = pytest.importorskip("playwright.sync_api")
    from pltf.client import MotionMode, OperationState, PlatformClient

    assert CHROMIUM.exists(), "make chromium installs Debian's chromium"
    run = PageRun(tmp_path)
    try:
        for block in _blocks("tutorials/gui.md"):
            run.run(block)
        url = f"http://127.0.0.1:{run.ports[8080]}/?target=127.0.0.1:{run.ports[10000]}"
        with sync_api.sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=["--no-sandbox", "--disable-gpu"])
            page = browser.new_page()
            page.goto(url, timeout=PATIENCE_MS)
            status = page.get_by_role("status", name="System state", exact=True)
            page.get_by_role("button", name="Init", exact=True).click()
            sync_api.expect(status).to_contain_text("Ready", timeout=PATIENCE_MS)
            page.get_by_role("combobox", name="Motion mode").select_option(label="Automatic")
            sync_api.expect(page.get_by_role("status", name="Motion mode", exact=True)).to_contain_text(
                "Automatic", timeout=PATIENCE_MS
            )
            page.get_by_role("button", name="Start", exact=True).click()
            sync_api.expect(status).to_contain_text("Running", timeout=PATIENCE_MS)
            browser.close()
        with PlatformClient("127.0.0.1", run.ports[10002], timeout=10.0) as other:
            seen = other.get_status()
        assert seen.operation_state == OperationState.ST_OP_RUNNING
        assert seen.motion_mode == MotionMode.MODE_MOTION_AUTOMATIC
    finally:
        run.close()
