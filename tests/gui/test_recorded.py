"""Time travel (issue 35): a patrol recorded through ``pltf proxy --record`` and opened with ``pltf gui --session``,
as a session file and as its MCAP export (``pltf export --mcap``, read in the page with @mcap/core).

The recording is made once per module with real processes: the reference server, ``pltf proxy --record`` in front
of its first port, and examples/patrol.py driving two stations through the proxy. The patrol asks GET_STATUS (never
GET_POSITION: checked), so the pose the GUI shows at a time is the estimated pose of the recording's last
GET_STATUS reply at or before it, read here from the session file with the proxy's own reader; the GUI shows it in
the status bar (its data-value: x, y mm, angle degrees), from the same topic the map view draws from.
"""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import urllib.error
import urllib.request
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pytest

from pltf.harness import launch
from pltf.proxy.session import read_session
from pltf.proxy.tap import FRAME
from tests.gui.conftest import PATIENCE, Gateway, wait_for

REPO = Path(__file__).resolve().parents[2]
STATIONS = "Corridor_01,Corridor_02"
FRACTIONS = (0.3, 0.55, 0.8)  # where the test scrubs to, of the recording's length


def _pltf(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "pltf.cli.main", *args]
    return subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=timeout, check=False)


def record_patrol(session: Path) -> None:
    """examples/patrol.py through ``pltf proxy --record SESSION`` against the reference server (real time: the
    5 m between the stations take ~9 s, ~20 GET_STATUS replies a second)."""
    with launch.reference(time_scale=1.0, start_timeout=60.0) as server:
        cmd = [sys.executable, "-m", "pltf.cli.main", "proxy", "--listen", "127.0.0.1:0", "--quiet"]
        cmd += ["--target", f"127.0.0.1:{server.ports[0]}", "--record", str(session)]
        with subprocess.Popen(cmd, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) as proxy:
            try:
                assert proxy.stdout is not None
                port = re.search(r"listening at [\d.]+:(\d+)", proxy.stdout.readline())
                assert port is not None, proxy.stderr.read() if proxy.stderr else ""
                patrol = [sys.executable, str(REPO / "examples" / "patrol.py"), "--stations", STATIONS]
                run = subprocess.run(
                    [*patrol, "--target", f"127.0.0.1:{port.group(1)}"],
                    cwd=REPO,
                    capture_output=True,
                    text=True,
                    timeout=180,
                    check=False,
                )
                assert run.returncode == 0, (run.stdout, run.stderr)
                proxy.send_signal(signal.SIGINT)
                _, err = proxy.communicate(timeout=30)
                assert proxy.returncode == 0, err
            finally:
                proxy.kill()


class Recording:
    """The recording as the test reads it: its GET_STATUS replies' poses and its commands."""

    def __init__(self, path: Path) -> None:
        frames = [r for r in read_session(path).records if r.kind == FRAME and r.telegram is not None]
        names = {r.telegram.NAME for r in frames}
        assert "CMD_GET_POSITION" not in names, "the patrol asks GET_POSITION now: compare with it instead"
        self.status = [
            (r.time, (r.telegram.est_x, r.telegram.est_y, r.telegram.est_angle / 1000))
            for r in frames
            if r.direction == "reply" and r.telegram.NAME == "CMD_GET_STATUS"
        ]
        self.commands = [
            r.telegram.NAME for r in frames if r.direction == "request" and not r.telegram.NAME.startswith("CMD_GET_")
        ]
        self.start, self.end = frames[0].time, frames[-1].time
        self.frames = frames

    def pose_at(self, t: float) -> tuple[float, ...]:
        before = [pose for at, pose in self.status if at <= t]
        assert before, f"no GET_STATUS reply at or before {t}"
        return before[-1]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Recording]:
    root = tmp_path_factory.mktemp("recorded")
    session, mcap = root / "patrol.jsonl", root / "patrol.mcap"
    record_patrol(session)
    exported = _pltf("export", str(session), "--mcap", str(mcap))
    assert exported.returncode == 0, exported.stderr
    for compression in ("zstd", "none"):  # pltf export's other compressions, for the page's reader
        other = mcap.with_name(f"patrol_{compression}.mcap")
        exported = _pltf("export", str(session), "--mcap", str(other), "--compression", compression)
        assert exported.returncode == 0, exported.stderr
    return session, mcap, Recording(session)


@pytest.fixture(scope="module", params=["session", "mcap"])
def shown(
    request: pytest.FixtureRequest, recorded: tuple[Path, Path, Recording]
) -> Iterator[tuple[Gateway, Recording]]:
    session, mcap, rec = recorded
    ini = session.parent / "Network.ini"
    ini.write_text("[Network]\n", encoding="utf-8")
    path = session if request.param == "session" else mcap
    with Gateway(ini, target=None, args=("--session", str(path))) as gw:
        yield gw, rec


def open_recording(page: Any, gw: Gateway) -> Any:
    page.goto(f"{gw.base}/?recording=1", timeout=30_000)
    timeline = page.get_by_role("region", name="Timeline")
    timeline.wait_for()
    return timeline


def shown_pose(page: Any) -> tuple[float, ...]:
    value = page.get_by_role("status", name="Estimated pose").get_attribute("data-value") or ""
    x, y, angle = value.split(",")
    return float(x), float(y), float(angle)


def scrub(page: Any, timeline: Any, start: float, rel: float) -> float:
    """Drag the scrubber to ``rel`` s into the recording (its input event, as a drag ends); the time shown."""
    scrubber = timeline.get_by_role("slider", name="Time in the recording")
    scrubber.evaluate("(el, v) => { el.value = v; el.dispatchEvent(new Event('input', { bubbles: true })); }", str(rel))
    return float(wait_for(lambda: _time_near(timeline, start + rel, 0.006), what=f"the timeline at {rel} s"))


def _time_near(timeline: Any, t: float, tol: float) -> str | None:
    shown = timeline.get_attribute("data-time")
    return shown if shown is not None and abs(float(shown) - t) <= tol else None


def test_scrubbing_shows_the_recorded_pose_and_play_ends_at_the_last_state(
    page: Any, shown: tuple[Gateway, Recording]
) -> None:
    gw, rec = shown
    timeline = open_recording(page, gw)
    start, end = float(timeline.get_attribute("data-start")), float(timeline.get_attribute("data-end"))
    assert abs(start - rec.start) < 1e-3 and abs(end - rec.end) < 1e-3, (start, end, rec.start, rec.end)
    seen = []
    for f in FRACTIONS:
        at = scrub(page, timeline, start, round(f * (end - start), 2))
        want = rec.pose_at(at)
        wait_for(lambda want=want: shown_pose(page) == want, what=f"pose {want} at {at}")
        seen.append(want)
    assert len(set(seen)) == len(FRACTIONS), seen  # the platform moved: each time shows its own pose
    # nothing can be sent: the operation buttons are disabled and the control line says why
    assert page.get_by_role("button", name="Start", exact=True).is_disabled()
    # play at 4x from the start: it ends at the recording's end, with its last state shown
    scrub(page, timeline, start, 0.0)
    timeline.get_by_role("combobox", name="Speed").select_option("4")
    timeline.get_by_role("button", name="Play").click()
    wait_for(lambda: timeline.get_attribute("data-playing") == "true", what="playing")
    wait_for(
        lambda: timeline.get_attribute("data-playing") == "false",
        timeout=PATIENCE + (end - start) / 4,
        what="the end of the recording",
    )
    assert abs(float(timeline.get_attribute("data-time") or 0) - end) < 1e-6
    wait_for(lambda: shown_pose(page) == rec.status[-1][1], what="the last state")


def test_the_commands_are_marks_on_the_timeline(page: Any, shown: tuple[Gateway, Recording]) -> None:
    gw, rec = shown
    timeline = open_recording(page, gw)
    marks = timeline.get_by_role("listitem")
    wait_for(lambda: marks.count() > 0, what="the marks")
    names = [m.get_attribute("data-name") for m in marks.all()]
    assert names == rec.commands, (names, rec.commands)
    assert set(names) >= {"CMD_MOVE_ABS"}, names  # the patrol's goals


def _wire_line(r: Any) -> str:
    """The wire inspector's line head of a frame: its UTC clock (ms, cut as JavaScript's Date cuts, from the whole µs
    of the recording: hog run 25 saw .924 shown for a frame at .925 when the page multiplied the seconds), arrow,
    name."""
    ms = round(r.time * 1e6) // 1000
    clock = datetime.fromtimestamp(ms // 1000, UTC).strftime("%H:%M:%S") + f".{ms % 1000:03d}"
    return f"{clock} {'->' if r.direction == 'request' else '<-'} {r.telegram.NAME}"


def test_a_click_on_a_mark_goes_there_and_the_wire_shows_the_telegrams_before_it(
    page: Any, shown: tuple[Gateway, Recording], recorded: tuple[Path, Path, Recording]
) -> None:
    gw, rec = shown
    timeline = open_recording(page, gw)
    wait_for(lambda: timeline.get_attribute("data-marks") == "all", what="every mark read")
    scrub(page, timeline, float(timeline.get_attribute("data-start")), 0.0)
    mark = timeline.get_by_role("listitem").last  # drawn on top of any it lies on
    at = float(mark.get_attribute("data-t") or 0)
    mark.click()
    wait_for(lambda: _time_near(timeline, at, 1e-6), what=f"the time of the mark, {at}")
    wait_for(lambda: shown_pose(page) == rec.pose_at(at), what=f"the pose at {at}")
    # the wire inspector: the recording's telegrams of the last second before the mark, as they passed
    page.get_by_role("tab", name="Wire Inspector").click()
    page.get_by_role("checkbox", name=re.compile("Hide polling")).uncheck()
    frames = [r for r in read_session(recorded[0]).records if r.kind == FRAME and r.telegram is not None]
    # the mark's time is its command's to the µs (an MCAP's log times are whole µs; the session's are rounded):
    # 1 µs of slack after it, so the command itself is among them
    want = [_wire_line(r) for r in frames if at - 1 < r.time <= at + 1e-6][-100:]
    assert want, at
    log = page.get_by_role("log", name="Wire Inspector")

    def tail() -> list[str] | None:
        lines = [" ".join(line.split(" ")[:3]) for line in log.inner_text().splitlines()]
        return lines[-len(want) :] if lines[-len(want) :] == want else None

    wait_for(tail, what=f"the wire's last {len(want)} lines: {want[-3:]}")


def test_a_recording_has_no_target(shown: tuple[Gateway, Recording]) -> None:
    gw, _ = shown
    with urllib.request.urlopen(f"{gw.base}/api/targets", timeout=10) as r:
        targets = json.load(r)
    assert targets["default"] is None and targets["fleet"] == [], targets
    assert all(not t.endswith(":1") for t in targets["targets"]), targets
    with pytest.raises(urllib.error.HTTPError) as ws:
        urllib.request.urlopen(f"{gw.base}/ws", timeout=10)
    ws.value.close()
    assert ws.value.code == 404


@pytest.mark.parametrize("compression", ["zstd", "none"])
def test_an_mcap_export_of_each_compression_opens_and_seeks(
    page: Any, recorded: tuple[Path, Path, Recording], compression: str
) -> None:
    """pltf export --compression zstd | none (lz4 is the default: the tests above): the page reads its chunks."""
    session, mcap, rec = recorded
    ini = session.parent / "Network.ini"
    ini.write_text("[Network]\n", encoding="utf-8")
    path = mcap.with_name(f"patrol_{compression}.mcap")
    with Gateway(ini, target=None, args=("--session", str(path))) as gw:
        timeline = open_recording(page, gw)
        start = float(timeline.get_attribute("data-start"))
        assert abs(start - rec.start) < 1e-3, (start, rec.start)
        for f in FRACTIONS:
            at = scrub(page, timeline, start, round(f * (rec.end - rec.start), 2))
            want = rec.pose_at(at)
            wait_for(lambda want=want: shown_pose(page) == want, what=f"pose {want} at {at} ({compression})")


def _wire_lines(page: Any) -> list[str]:
    log = page.get_by_role("log", name="Wire Inspector")
    return [" ".join(line.split(" ")[:3]) for line in log.inner_text().splitlines()]


def _battery(page: Any) -> str:
    pane = page.get_by_role("tabpanel", name="IOBoard", exact=True)
    return pane.get_by_role("row").filter(has_text="Battery").get_by_role("cell").inner_text().strip()


def test_a_jump_shows_the_state_at_its_time_only(page: Any, shown: tuple[Gateway, Recording]) -> None:
    """After a jump every panel shows the state at t alone: before the first status reply no platform on the map
    and an empty hardware monitor; the wire inspector holds the telegrams of the second before t, none of an
    earlier seek's."""
    gw, rec = shown
    timeline = open_recording(page, gw)
    start = float(timeline.get_attribute("data-start"))
    canvas = page.locator("canvas.map-canvas")
    page.get_by_role("tab", name="Wire Inspector").click()
    page.get_by_role("checkbox", name=re.compile("Hide polling")).uncheck()

    def wire_at(at: float) -> list[str]:
        # data-time is the recording's time to the µs (an MCAP's log times are whole µs): 1 µs of slack after it
        return [_wire_line(r) for r in rec.frames if at - 1 < r.time <= at + 1e-6][-100:]

    first_status = rec.status[0][0]
    for rel in (0.55 * (rec.end - rec.start), 0.0, 0.3 * (rec.end - rec.start)):
        at = scrub(page, timeline, start, round(rel, 2))
        want = wire_at(at)
        try:
            wait_for(lambda want=want: _wire_lines(page) == want, what=f"only the wire's {len(want)} lines before {at}")
        except AssertionError as exc:  # what was shown instead (hog run 20 saw this fail once, without it)
            shown, now = _wire_lines(page), timeline.get_attribute("data-time")
            extra, missing = [x for x in shown if x not in want], [x for x in want if x not in shown]
            raise AssertionError(
                f"{exc}; timeline at {now}; shown but not wanted {extra}; wanted, not shown {missing}"
            ) from None
        page.wait_for_timeout(700)  # the plots' history comes 250 ms after a jump: the wire keeps its lines
        assert _wire_lines(page) == want, at
        if at >= first_status:
            pose = rec.pose_at(at)
            wait_for(
                lambda pose=pose: (
                    tuple(map(float, (canvas.get_attribute("data-platform") or "0,0,0").split(","))) == pose
                ),
                what=f"the platform drawn at {pose}",
            )
        else:
            wait_for(lambda: canvas.get_attribute("data-platform") is None, what="no platform before the first status")
    # the hardware monitor: the battery of the status at 0.3, then nothing before the first status
    page.get_by_role("tab", name="Hardware Monitor").click()
    page.get_by_role("tab", name="IOBoard", exact=True).click()
    wait_for(lambda: _battery(page).endswith(" V"), what="the battery shown")
    scrub(page, timeline, start, 0.0)
    assert start < first_status
    wait_for(lambda: _battery(page) == "", what="no battery before the first status")
    wait_for(lambda: canvas.get_attribute("data-platform") is None, what="no platform before the first status")
