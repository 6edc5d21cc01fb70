"""The timeline's keyboard (panels/timeline.ts, issue 35): Space plays and pauses, the arrows step 0.5 s (Shift: 10 s),
Home and End go to the ends; the status bar follows. The recording is benchmarks/bench_mcap.py's (20 Hz GET_STATUS
polling, the platform on a circle), 20 s of it, written with the proxy's SessionWriter."""

from __future__ import annotations

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
    write_recording(session, SECONDS)
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


def _status_count(poses: list[Any], t: float, span: float = 60.0) -> int:
    return sum(1 for when, _ in poses if t - span < when <= t)


def test_a_jump_before_the_first_reply_shows_no_status_and_the_plots_end_at_the_time(
    page: Any, circle: tuple[Gateway, list[Any]]
) -> None:
    gw, poses = circle
    page.goto(f"{gw.base}/?recording=circle.jsonl", timeout=30_000)
    timeline = page.get_by_role("region", name="Timeline")
    timeline.wait_for()
    start = float(timeline.get_attribute("data-start"))
    pose = page.get_by_role("status", name="Estimated pose")
    page.get_by_role("tab", name="Plots").click()
    velocity = page.get_by_role("img", name="Velocity")
    for t in (start + 15.0, start + 5.0, start + 12.5):  # forward, back, forward again: each a jump
        page.evaluate("(t) => window.pltf.timeline.seek(t)", t)
        want = [p for when, p in poses if when <= t][-1]
        wait_for(lambda want=want: _pose(page) == want, what=f"the pose at {t}")
        # the plots hold the recording's statuses up to t (the window's 60 s), none after it
        n = _status_count(poses, t)
        wait_for(lambda n=n: velocity.get_attribute("data-points") == str(n), what=f"{n} points at {t}")
    # the recording starts with a request: at its start no status has been answered yet
    page.keyboard.press("Home")
    wait_for(lambda: pose.get_attribute("data-value") is None, what="no pose before the first reply")
    assert pose.inner_text().strip().endswith("-"), pose.inner_text()
    wait_for(lambda: velocity.get_attribute("data-points") == "0", what="an empty plot")
    page.keyboard.press("ArrowRight")  # 0.5 s in: the status is back
    wait_for(lambda: _pose(page) == [p for when, p in poses if when <= start + 0.5][-1], what="the pose again")


def test_the_timeline_in_german(page: Any, circle: tuple[Gateway, list[Any]]) -> None:
    gw, _ = circle
    page.add_init_script("localStorage.setItem('pltf.lang', 'de')")
    page.goto(f"{gw.base}/?recording=circle.jsonl", timeout=30_000)
    timeline = page.get_by_role("region", name="Zeitleiste")
    timeline.wait_for()
    assert timeline.get_by_role("slider", name="Zeit in der Aufzeichnung").is_visible()
    assert timeline.get_by_role("combobox", name="Geschwindigkeit").is_visible()
    timeline.get_by_role("button", name="Abspielen").click()
    timeline.get_by_role("button", name="Anhalten").click()
    wait_for(lambda: timeline.get_attribute("data-playing") == "false", what="paused")
    note = "Eine Aufzeichnung wird gezeigt: nichts wird an eine Plattform gesendet."
    assert note in timeline.inner_text(), timeline.inner_text()
