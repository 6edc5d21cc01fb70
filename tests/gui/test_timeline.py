"""The timeline's keyboard (panels/timeline.ts, issue 35): Space plays and pauses, the arrows step 0.5 s (Shift: 10 s),
Home and End go to the ends; the status bar follows. The recording is benchmarks/bench_mcap.py's (20 Hz GET_STATUS
polling, the platform on a circle), 20 s of it, written with the proxy's SessionWriter."""

from __future__ import annotations

import gc
import warnings
from collections.abc import Iterator
from typing import Any

import pytest

from benchmarks.bench_mcap import write_recording
from pltf.proxy.session import read_session
from tests.gui.conftest import Gateway, wait_for

SECONDS = 20.0


@pytest.fixture(scope="module")
def circle(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Gateway, list[tuple[float, tuple[float, ...]]]]]:
    root = tmp_path_factory.mktemp("timeline")
    session = root / "circle.jsonl"
    with warnings.catch_warnings():  # write_recording leaves its SessionWriter's first file to the collector
        warnings.simplefilter("ignore", ResourceWarning)
        write_recording(session, SECONDS)
        gc.collect()
    poses = [
        (r.time, (r.telegram.est_x, r.telegram.est_y, r.telegram.est_angle / 1000))
        for r in read_session(session).records
        if r.direction == "reply" and r.telegram is not None
    ]
    (root / "Network.ini").write_text("[Network]\n", encoding="utf-8")
    with Gateway(root / "Network.ini", target=None, args=("--session", str(session))) as gw:
        yield gw, poses


def _pose(page: Any) -> tuple[float, ...]:
    x, y, angle = (page.get_by_role("status", name="Estimated pose").get_attribute("data-value") or "0,0,0").split(",")
    return float(x), float(y), float(angle)


def test_space_plays_and_pauses_and_the_arrows_step(page: Any, circle: tuple[Gateway, list[Any]]) -> None:
    gw, poses = circle
    page.goto(f"{gw.base}/?recording=circle.jsonl", timeout=30_000)
    timeline = page.get_by_role("region", name="Timeline")
    timeline.wait_for()
    start, end = float(timeline.get_attribute("data-start")), float(timeline.get_attribute("data-end"))

    def at(t: float) -> None:
        wait_for(lambda: abs(float(timeline.get_attribute("data-time") or 0) - t) < 1e-6, what=f"the time {t}")
        before = [pose for when, pose in poses if when <= t]
        if before:  # the recording starts with a request: its first reply is 2 ms later
            want = before[-1]
            wait_for(lambda: _pose(page) == want, what=f"the pose {want} at {t}")

    at(start)
    for key, t in [
        ("ArrowRight", start + 0.5),
        ("Shift+ArrowRight", start + 10.5),
        ("ArrowLeft", start + 10.0),
        ("End", end),
        ("Home", start),
    ]:
        page.keyboard.press(key)
        at(t)
    page.keyboard.press("Space")
    wait_for(lambda: timeline.get_attribute("data-playing") == "true", what="playing")
    wait_for(lambda: float(timeline.get_attribute("data-time") or 0) > start + 0.2, what="the time moving")
    page.keyboard.press("Space")
    wait_for(lambda: timeline.get_attribute("data-playing") == "false", what="paused")
    page.wait_for_timeout(300)  # a seek asked before the pause is shown
    paused = float(timeline.get_attribute("data-time") or 0)
    assert start < paused < end
    page.wait_for_timeout(300)
    assert float(timeline.get_attribute("data-time") or 0) == paused  # paused stays put
    # a recording sends nothing: the session refuses, with the reason
    refused = page.evaluate(
        "() => window.pltf.session.request({ telegramName: 'CMD_STOP' }).then(() => 'sent', (e) => e.message)"
    )
    assert refused == "CMD_STOP not sent: a recording is shown", refused
