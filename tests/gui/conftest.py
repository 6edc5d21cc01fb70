"""Fixtures of the GUI tests: the reference server (a subprocess, with its fault-control channel), the gateway
(``pltf gui`` as a subprocess), Debian's chromium driven by Playwright, and a plain client on the server's OTHER
port to check what the GUI did.

A page fixture fails the test on any browser console error or uncaught page error. Screenshots go to
``$PLTF_GUI_ARTIFACTS`` (default: a ``gui-artifacts`` folder in pytest's temporary directory).
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import socket
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from pltf.client import PlatformClient
from pltf.gui.launch import GatewayProcess as Gateway
from pltf.harness import launch

REPO = Path(__file__).resolve().parents[2]
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
VIEWPORT = {"width": 1400, "height": 900}
# How long a wait or a page expectation may take before it fails: a guard against a hang, never a speed
# assertion. The browser, the gateway and the platform share two cores with the other test worker (pytest -n 2);
# two browser tests failed once each in loaded full runs and passed when run again (their output was not kept),
# so the guard is generous rather than tight.
PATIENCE = 30.0  # s

playwright_sync = pytest.importorskip("playwright.sync_api")


def _need_browser() -> None:
    if not Path(CHROMIUM).exists():
        pytest.fail(f"{CHROMIUM} is missing: `make chromium` installs Debian's chromium")
    static = Path(os.environ.get("PLTF_GUI_STATIC") or REPO / "gui" / "static")
    if not (static / "index.html").is_file():
        pytest.fail(f"the GUI is not built in {static}: `make gui`")


def wait_for(pred: Callable[[], Any], timeout: float = PATIENCE, what: str = "condition", every: float = 0.05) -> Any:
    deadline = time.monotonic() + timeout
    while True:
        value = pred()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(every)


def _to_page(cam: dict[str, float], box: dict[str, float], x: float, y: float) -> tuple[float, float]:
    return (
        box["x"] + (x - cam["cx"]) * cam["scale"] + cam["width"] / 2,
        box["y"] + (cam["cy"] - y) * cam["scale"] + cam["height"] / 2,
    )


def page_point(page: Any, x: float, y: float) -> tuple[float, float]:
    """The page coordinates of the world point (x, y) mm on the map view, as its camera was last drawn."""
    canvas = page.get_by_role("img", name="Map")
    return _to_page(json.loads(canvas.get_attribute("data-camera")), canvas.bounding_box(), x, y)


View = tuple[dict[str, float], dict[str, float]]  # the map view's camera (data-camera) and its canvas box


class _ViewWatch:
    """Looks at the map view twice, ``settle`` s apart; remembers what it saw last for the failure message."""

    WATCHED = ("data-camera", "data-layer", "data-drawn-line")

    def __init__(self, page: Any, settle: float) -> None:
        self.canvas = page.get_by_role("img", name="Map")
        self.settle = settle
        self.last: tuple[Any, ...] = ()

    def look(self) -> tuple[Any, ...]:
        return (*(self.canvas.get_attribute(a) for a in self.WATCHED), self.canvas.bounding_box())

    def settled(self) -> View | None:
        before = self.look()
        time.sleep(self.settle)
        self.last = now = self.look()
        camera, layer, lines, box = now
        if now != before or camera is None or box is None or layer != "current" or int(str(lines or 0)) == 0:
            return None
        return json.loads(camera), box

    def wait(self, pred: Callable[[], Any], what: str) -> Any:
        try:
            return wait_for(pred, what=what)
        except AssertionError as e:
            seen = dict(zip((*self.WATCHED, "box", "on top"), self.last, strict=False))
            raise AssertionError(f"{e}; last seen: {seen}") from None


def settled_view(page: Any, settle: float = 0.15) -> View:
    """The map view's camera (data-camera) and canvas box once the view has settled.

    Settled: a map with lines drawn (``data-drawn-line``; every map the tests edit has walls), the layer current,
    the camera and the canvas box the same over ``settle`` s. A position read while the view is about to change -
    the platform's map arriving and being fitted just after connecting, a dock pane opening beside the canvas -
    sends the pointer somewhere else (CI, stop 26: the roadmap editor test's first station was never added; before
    the map is fitted, y 9910 mm lies ~500 px above the centre of the default camera, off the canvas)."""
    watch = _ViewWatch(page, settle)
    got: View = watch.wait(watch.settled, "the map view settled")
    return got


# what the page has at a point: the canvas itself, or the tag and class of what lies over it there
_ON_TOP = """(canvas, [x, y]) => {
  const e = document.elementFromPoint(x, y);
  return e === canvas ? "canvas" : e === null ? "nothing" : `${e.tagName.toLowerCase()}.${e.className}`;
}"""


def aim(page: Any, x: float, y: float, settle: float = 0.15) -> tuple[float, float]:
    """Where to put the pointer for the world point (x, y) mm: on the settled view, inside the canvas, and with
    nothing over the canvas there (``page.mouse`` clicks whatever lies on top, unlike a locator's click)."""
    watch = _ViewWatch(page, settle)

    def clear() -> tuple[float, float] | None:
        view = watch.settled()
        if view is None:
            return None
        sx, sy = _to_page(*view, x, y)
        top = watch.canvas.evaluate(_ON_TOP, [sx, sy])
        watch.last = (*watch.last, f"at ({sx:.0f}, {sy:.0f}): {top}")
        return (sx, sy) if top == "canvas" else None

    got: tuple[float, float] = watch.wait(clear, f"the map view settled with ({x}, {y}) in sight")
    return got


class Control:
    """The reference server's fault-control channel (fake_hardware/control_channel.py): one line, one JSON answer."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)
        self.file = self.sock.makefile("rwb")

    def __call__(self, line: str) -> dict[str, Any]:
        self.file.write(line.encode() + b"\n")
        self.file.flush()
        answer: dict[str, Any] = json.loads(self.file.readline())
        assert answer.get("ok"), answer
        return answer

    def close(self) -> None:
        self.file.close()
        self.sock.close()


class Platform:
    """A running reference server: its two ports, its control channel, a client on the second port."""

    def __init__(self, server: launch.Launched) -> None:
        self.server = server
        self.ports = server.ports
        found = wait_for(
            lambda: re.findall(r"control channel started at port (\d+)", "\n".join(server.log_lines)),
            timeout=10,
            what="the control channel",
        )
        self.control = Control(int(found[0]))
        self._other: PlatformClient | None = None

    @property
    def target(self) -> str:
        return f"127.0.0.1:{self.ports[0]}"

    @property
    def other(self) -> PlatformClient:
        """A plain client on the port the GUI does not use (guide 6.1: 10000 and 10002)."""
        if self._other is None:
            self._other = PlatformClient("127.0.0.1", self.ports[1], timeout=5.0)
        return self._other

    def close(self) -> None:
        if self._other is not None:
            self._other.close()
        self.control.close()


@pytest.fixture
def platform() -> Iterator[Platform]:
    with launch.reference(time_scale=5.0, extra=["--control-port", "0"], start_timeout=60.0) as server:
        p = Platform(server)
        try:
            yield p
        finally:
            p.close()


@pytest.fixture(scope="session")
def gateway(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Gateway]:
    _need_browser()
    ini = tmp_path_factory.mktemp("gui") / "Network.ini"
    ini.write_text("[Network]\nlab = 127.0.0.1:10000\n", encoding="utf-8")
    with Gateway(ini, reply_timeout=2.0) as gw:  # its log goes to a file: a pipe nobody reads stalls it at 64 KB
        yield gw


# Package scope: Playwright's sync API keeps an asyncio loop marked running in the main thread while it is open,
# so later packages' ``asyncio.run`` (pltf replay, pltf proxy) would refuse to start if it stayed open.
@pytest.fixture(scope="package")
def browser() -> Iterator[Any]:
    _need_browser()
    with playwright_sync.sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            yield b
        finally:
            b.close()


@pytest.fixture(scope="session")
def artifacts(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = os.environ.get("PLTF_GUI_ARTIFACTS")
    path = Path(out) if out else tmp_path_factory.mktemp("gui-artifacts")
    path.mkdir(parents=True, exist_ok=True)
    return path


@contextlib.contextmanager
def checked_page(browser: Any, **context: Any) -> Iterator[Any]:
    """A page in a new browser context (``context``: Playwright's new_context options, the viewport by default);
    any console error or page error it reported fails the test at the end."""
    ctx = browser.new_context(**{"viewport": VIEWPORT, **context})
    pg = ctx.new_page()
    problems: list[str] = []
    pg.on("console", lambda m: problems.append(f"console {m.type}: {m.text}") if m.type == "error" else None)
    pg.on("pageerror", lambda e: problems.append(f"page error: {e}"))
    pg.set_default_timeout(PATIENCE * 1000)
    try:
        yield pg
    finally:
        ctx.close()
    assert not problems, "the browser reported errors:\n" + "\n".join(problems)


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    with checked_page(browser) as pg:
        yield pg


def open_gui(page: Any, gateway: Gateway, target: str, *, connected: bool = True) -> None:
    page.goto(gateway.url(target), timeout=30_000)  # the gateway shares 2 cores with the server and the browser
    if connected:
        expect_text(page.get_by_role("status", name="Connection"), f"connected to {target}")


def expect_text(locator: Any, text: str | re.Pattern[str], timeout: float = PATIENCE * 1000) -> None:
    playwright_sync.expect(locator).to_contain_text(text, timeout=timeout)
