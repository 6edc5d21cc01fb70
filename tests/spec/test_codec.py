"""pltf.spec.codec's telegram sets: compiled on first use, one class per telegram whichever way it is reached."""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

from pltf.spec import codec
from pltf.spec.codec import REPLIES, REQUESTS, TelegramSet, decode_frame, encode
from pltf.spec.compiler import compile_telegram
from pltf.spec.model import load_telegrams, telegram_def


def test_every_route_to_a_telegram_gives_the_one_class() -> None:
    for tdef in load_telegrams():
        cls = REQUESTS.by_id[tdef.id]
        assert REQUESTS[tdef.name] is cls and getattr(REQUESTS, tdef.name) is cls and REQUESTS.by_name[tdef.name] is cls
        assert all(REQUESTS.by_name[alias] is cls for alias in tdef.aliases)
        assert (tdef.id, tdef.name, "request", tdef) == (cls.ID, cls.NAME, cls.DIRECTION, cls.DEF)
    assert list(REQUESTS) == [REQUESTS.by_id[t.id] for t in load_telegrams()]  # ordered by id


def test_the_sets_know_every_telegram_before_compiling_it() -> None:
    tdefs = load_telegrams()
    fresh = TelegramSet("request", tdefs)
    assert len(fresh) == len(tdefs) == len(REQUESTS) and not fresh._done
    assert 15 in fresh.by_id and "CMD_SET_MODE" in fresh.by_name and 250 not in fresh.by_id
    assert not fresh._done  # membership compiles nothing
    assert fresh.decode_data(bytes([15, 0, 0, 0, 3])).mode == 3  # type: ignore[attr-defined]
    assert list(fresh._done) == [15]
    assert len(REPLIES) == sum(1 for t in tdefs if t.reply is not None or not t.layout_known)


def test_threads_compiling_at_once_share_one_class_and_can_encode_it(monkeypatch: pytest.MonkeyPatch) -> None:
    def slow_compile(*args: Any) -> Any:
        time.sleep(0.02)  # every thread is inside the compiler at once
        return compile_telegram(*args)

    monkeypatch.setattr(codec, "compile_telegram", slow_compile)
    fresh = TelegramSet("request", load_telegrams())
    barrier = threading.Barrier(8)
    got: list[type] = []

    def first_use() -> None:
        barrier.wait()
        got.append(fresh.by_name["CMD_MOVE_ABS"])

    threads = [threading.Thread(target=first_use) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(set(got)) == 1
    telegram = got[0](x=1000, y=-5, angle=90)
    assert fresh.encode_data(telegram) == bytes([telegram_def("CMD_MOVE_ABS").id]) + bytes.fromhex(
        "000003e8fffffffb0000005a"
    )


def test_the_module_sets_encode_and_decode_as_before() -> None:
    frame = bytes.fromhex("ff01fe02000000050f00000003")
    telegram = decode_frame(frame, "request")
    assert telegram == REQUESTS.CMD_SET_MODE(mode=3) and encode(telegram) == frame
