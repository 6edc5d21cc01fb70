"""The gateway's sans-IO core: FIFO routing of replies to tabs, coalescing, refusal of bad frames and replies."""

from __future__ import annotations

import pytest

from pltf.gui.routing import ANSWERED, BadRequest, ReplyMismatch, Router, check_request
from pltf.spec import errors
from pltf.spec.codec import REPLIES, REQUESTS, encode
from tests.clients.client_fakes import status_telegram

STATUS_REQ = encode(REQUESTS.CMD_GET_STATUS())
MAP_REQ = encode(REQUESTS.CMD_GET_MAP())
START = encode(REQUESTS.CMD_START())
STATUS_REPLY = encode(status_telegram(est_x=1234))
MAP_REPLY = encode(REPLIES.CMD_GET_MAP(xml="<map/>", name="m"))


def test_only_the_spec_s_answered_telegrams_wait_for_a_reply() -> None:
    assert set(ANSWERED.values()) >= {"CMD_GET_STATUS", "CMD_GET_MAP", "CMD_GET_PLTF_PARAM"}
    assert "CMD_START" not in ANSWERED.values() and "CMD_DEBUG1" not in ANSWERED.values()
    r = Router()
    assert r.submit("a", START, 0.0) == START
    assert not r.pending


def test_replies_go_to_the_tab_that_asked_in_fifo_order_however_the_bytes_are_split() -> None:
    r = Router()
    assert r.submit("a", STATUS_REQ, 0.0) == STATUS_REQ
    assert r.submit("b", MAP_REQ, 0.1) == MAP_REQ
    stream = STATUS_REPLY + MAP_REPLY
    got = []
    for i in range(0, len(stream), 7):
        got += [(frame, entry.tabs) for frame, entry in r.receive_data(stream[i : i + 7])]
    assert got == [(STATUS_REPLY, ["a"]), (MAP_REPLY, ["b"])]
    assert r.oldest() is None


def test_an_identical_pending_request_is_joined_not_sent_again() -> None:
    r = Router()
    assert r.submit("a", STATUS_REQ, 0.0) == STATUS_REQ
    assert r.submit("b", STATUS_REQ, 0.0) is None
    [(_, entry)] = list(r.receive_data(STATUS_REPLY))
    assert entry.tabs == ["a", "b"] and entry.coalesced == 1


def test_joining_never_reorders_a_tab_s_own_replies() -> None:
    r = Router()
    r.submit("a", STATUS_REQ, 0.0)
    r.submit("b", MAP_REQ, 0.0)
    # b waits for the map; joining a's earlier GET_STATUS would hand b the status first
    assert r.submit("b", STATUS_REQ, 0.0) == STATUS_REQ
    assert [e.tabs for e in r.pending] == [["a"], ["b"], ["b"]]


def test_a_reply_nobody_asked_for_and_a_malformed_reply_are_errors() -> None:
    r = Router()
    r.submit("a", MAP_REQ, 0.0)
    with pytest.raises(ReplyMismatch, match="waiting for CMD_GET_MAP"):
        list(r.receive_data(STATUS_REPLY))
    r.reset()
    r.submit("a", STATUS_REQ, 0.0)
    with pytest.raises(errors.BadHeader):
        list(r.receive_data(b"garbage!"))


def test_bad_frames_from_a_tab_are_refused_before_the_platform() -> None:
    for bad in (b"", b"\xff\x01\xfe\x02", STATUS_REQ + b"x", b"\xff\x01\xfe\x02\x00\x00\x00\x01\xee"):
        with pytest.raises(BadRequest):
            check_request(bad)
    assert check_request(STATUS_REQ) == 18


def test_reset_returns_what_was_pending_and_forget_drops_a_tab() -> None:
    r = Router()
    r.submit("a", STATUS_REQ, 1.5)
    r.submit("b", MAP_REQ, 2.0)
    assert r.oldest() == 1.5
    r.forget("a")
    assert [e.tabs for e in r.pending] == [[], ["b"]]
    assert [e.telegram_id for e in r.reset()] == [18, 26]
    assert not r.pending
