"""proxy/view.py: one line per record, enums by name, groups by count; the selection by telegram name."""

from __future__ import annotations

import io

from pltf.proxy.tap import CLOSE, Record, Tap
from pltf.proxy.view import Selection, View, format_record
from pltf.spec.codec import build, encode


def _rec(direction: str, name: str, **fields: object) -> Record:
    (rec,) = Tap(direction, 3, 10002).feed(encode(build(direction, name, **fields)), 0.25)  # type: ignore[arg-type]
    return rec


def test_lines() -> None:
    style, line = format_record(_rec("request", "CMD_SET_MODE", mode=4), t0=0.0)
    assert style == "request" and line == "     0.250 #3   :10002 -> CMD_SET_MODE mode=MODE_MOTION_AUTOMATIC(4)"
    frames = tuple((i, 2 * i, 0) for i in range(5))
    _, line = format_record(_rec("request", "CMD_MOVE_PATH", frames=frames), t0=0.0)
    assert line.endswith("CMD_MOVE_PATH frames=[5: {x=0 y=0 angle=0}, {x=1 y=2 angle=0}, {x=2 y=4 angle=0}, ...]")
    _, line = format_record(_rec("reply", "CMD_GET_CAMERA", ip="x" * 50, camera_id="c"), t0=0.0)
    assert f"ip='{'x' * 40}...' camera_id='c'" in line
    (bad,) = Tap("reply", 1, 10000).feed(bytes.fromhex("fe01fe020000000112"), 1.0)
    style, line = format_record(bad, t0=0.0)
    assert style == "malformed" and "<- MALFORMED BadHeader: bad header fe01fe02" in line and "9 bytes: fe01" in line
    style, line = format_record(Record(2.0, 1, 10000, CLOSE, detail="by target (FIN)"), t0=0.0)
    assert style == "event" and line.endswith("close by target (FIN)")


def test_selection() -> None:
    status, stop = _rec("request", "CMD_GET_STATUS"), _rec("request", "CMD_STOP")
    (bad,) = Tap("request", 1, 1).feed(b"\x00", 0.0)
    assert Selection(["get_status"]).shows(status) and not Selection(["get_status"]).shows(stop)
    assert Selection(["CMD_GET_*"]).shows(status) and not Selection(hide=["GET_STATUS"]).shows(status)
    assert Selection(["CMD_MOVE_*"]).shows(bad)  # malformed bytes always show


def test_view_cuts_lines_and_colours_only_when_asked() -> None:
    out = io.StringIO()
    view = View(out, Selection(hide=["CMD_STOP"]), width=40, t0=0.0)
    for rec in (_rec("request", "CMD_MOVE_PATH", frames=((1, 2, 3),) * 9), _rec("request", "CMD_STOP")):
        view.show(rec)
    (line,) = out.getvalue().splitlines()
    assert len(line) == 40 and line.endswith("...") and "\x1b" not in line
    coloured = io.StringIO()
    View(coloured, color=True).show(_rec("request", "CMD_STOP"))
    assert coloured.getvalue().startswith("\x1b[36m")
