"""proxy/offload.py: the recorder in its own process gets every event in order and writes the same session file
as an in-process one; a recorder process that died stops recording, not the caller."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

from pltf.proxy.capture import PcapngWriter
from pltf.proxy.offload import RecorderPipe
from pltf.proxy.recorder import Recorder
from pltf.proxy.session import Route, SessionWriter, read_session

STOP = bytes.fromhex("ff01fe02000000010e")
POSITION = bytes.fromhex("ff01fe02000000214a000007d000002710000000000000000000000000000000000000000000000000")


def _events(target: object) -> None:
    call = target.__getattribute__
    call("opened")(1, 10.0, 10000, ("127.0.0.1", 5000), ("127.0.0.1", 10000))
    call("data")(1, 10.1, True, STOP + bytes.fromhex("ff01fe02000000014a")[:5])
    call("data")(1, 10.2, True, bytes.fromhex("ff01fe02000000014a")[5:])
    call("data")(1, 10.3, False, POSITION * 3)
    call("data")(1, 10.4, True, b"\x00garbage")
    call("half_closed")(1, 10.5, True)
    call("closed")(1, 10.6, "by client (FIN)", 10.5)


def _make(path: Path) -> Recorder:
    return Recorder([], PcapngWriter(path.with_suffix(".pcapng")), SessionWriter(path))


def test_the_recorder_process_writes_what_an_in_process_recorder_writes(tmp_path: Path) -> None:
    routes = [Route("127.0.0.1:20000", "127.0.0.1:10000")]
    here = _make(tmp_path / "here.jsonl")
    assert here.session is not None
    here.session.start(routes, 9.0)
    _events(here)
    here.close(11.0)
    pipe = RecorderPipe(lambda: _make(tmp_path / "there.jsonl"), lambda r: f"{r.counts['malformed']} malformed")
    pipe.start()
    pipe.session_start([(r.listen, r.target) for r in routes], 9.0)
    _events(pipe)
    pipe.close(11.0)
    assert (tmp_path / "there.jsonl").read_text() == (tmp_path / "here.jsonl").read_text()
    assert (tmp_path / "there.pcapng").read_bytes() == (tmp_path / "here.pcapng").read_bytes()
    names = [r.name for r in read_session(tmp_path / "there.jsonl").records]
    assert names == [
        "open",
        "CMD_STOP",
        "CMD_GET_POSITION",
        "CMD_GET_POSITION",
        "CMD_GET_POSITION",
        "CMD_GET_POSITION",
        "malformed",
        "close",
    ]


def test_a_dead_recorder_process_stops_recording_not_the_caller(tmp_path: Path) -> None:
    pipe = RecorderPipe(lambda: _make(tmp_path / "s.jsonl"), lambda r: "")
    pipe.start()
    os.kill(pipe.pid, signal.SIGKILL)
    os.waitpid(pipe.pid, 0)
    with pytest.raises(RuntimeError, match="recorder process is gone"):
        for _ in range(100):
            pipe.data(1, 1.0, True, STOP)
            pipe.flush()
    pipe.data(1, 1.0, True, STOP)  # from then on: nothing, no error
    pipe.flush()
    pipe.close(2.0)
