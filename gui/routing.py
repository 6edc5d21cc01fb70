"""Which tab gets which reply: the gateway's sans-IO core (no sockets, no clock).

Rules:
- Every tab's request frames go to the one platform connection in the order they arrive (FIFO over all tabs).
- Guide 6.1: the platform "returns data only on request": only telegrams with a `reply` in spec/telegrams.yaml
  (``TelegramDef.answered``) are answered. Those are queued as pending; every other frame is sent and forgotten.
- Replies come back in request order (one connection, answered in turn), so the head of the pending queue
  owns the next reply frame. A reply of another identifier means the stream is out of step: ``ReplyMismatch``,
  and the caller drops the connection.
- An answered request whose bytes equal a request already pending is not sent again: the tab joins that
  entry and gets the same reply (several tabs polling GET_STATUS cost the platform one request), as long as
  this keeps the tab's own replies in its order (it has nothing pending at or after that entry).
- The frames are checked whole (header, length, a request identifier of the spec); a tab's bad frame is
  refused (``BadRequest``) and never reaches the platform. Telegrams are not interpreted otherwise.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Hashable, Iterator
from dataclasses import dataclass, field

from pltf.spec import errors
from pltf.spec.codec import FRAME_OVERHEAD, HEADER, REPLIES, REQUESTS, TelegramDecoder
from pltf.spec.model import load_telegrams
from pltf.spec.telegram import Telegram

# identifier -> telegram name, for the requests that are answered (guide 6.1)
ANSWERED: dict[int, str] = {t.id: t.name for t in load_telegrams() if t.answered}


class BadRequest(ValueError):
    """A tab sent bytes that are not one request frame of the spec."""


class ReplyMismatch(ValueError):
    """A reply arrived that no pending request asked for: the stream is out of step."""


@dataclass
class Pending:
    """One answered request on the wire and the tabs that wait for its reply."""

    telegram_id: int
    frame: bytes
    tabs: list[Hashable]
    sent_at: float
    coalesced: int = 0


def check_request(frame: bytes) -> int:
    """The identifier of a whole request frame; ``BadRequest`` for anything else."""
    if len(frame) <= FRAME_OVERHEAD or frame[:4] != HEADER:
        raise BadRequest("not a request frame (header FF 01 FE 02, length, data)")
    if int.from_bytes(frame[4:8], "big") != len(frame) - FRAME_OVERHEAD:
        raise BadRequest("the frame's length field does not match its data")
    try:
        REQUESTS.decode_data(frame[FRAME_OVERHEAD:])
    except errors.RemoteProtocolError as exc:
        raise BadRequest(f"not a valid request: {exc}") from None
    return frame[FRAME_OVERHEAD]


@dataclass
class Router:
    """The pending replies of one platform connection, and the reply stream's framing."""

    pending: deque[Pending] = field(default_factory=deque)
    _decoder: TelegramDecoder = field(default_factory=lambda: TelegramDecoder("reply"))
    _raw: deque[bytes] = field(default_factory=deque)

    def __post_init__(self) -> None:
        self._decoder = TelegramDecoder("reply", decode_data=self._decode_data)

    def _decode_data(self, data: bytes) -> Telegram:
        telegram = REPLIES.decode_data(data)  # malformed replies raise RemoteProtocolError here
        self._raw.append(data)
        return telegram

    def submit(self, tab: Hashable, frame: bytes, now: float) -> bytes | None:
        """A tab's request: the bytes to send to the platform, or None when it joined a pending request."""
        telegram_id = check_request(frame)
        if telegram_id not in ANSWERED:
            return frame
        for entry in reversed(self.pending):
            if tab in entry.tabs:
                break  # the tab already waits at or after this point: joining an earlier entry would reorder it
            if entry.frame == frame:
                entry.tabs.append(tab)
                entry.coalesced += 1
                return None
        self.pending.append(Pending(telegram_id, frame, [tab], now))
        return frame

    def receive_data(self, data: bytes) -> Iterator[tuple[bytes, Pending]]:
        """Feed bytes from the platform; yields (reply frame, the entry it answers).

        Raises RemoteProtocolError (malformed reply) or ReplyMismatch (a reply nobody asked for).
        """
        self._decoder.receive_data(data)
        while (telegram := self._decoder.next_telegram()) is not None:
            raw = self._raw.popleft()
            if not self.pending or self.pending[0].telegram_id != telegram.ID:
                wanted = ANSWERED[self.pending[0].telegram_id] if self.pending else "nothing"
                raise ReplyMismatch(f"a {telegram.NAME} reply arrived while waiting for {wanted}")
            yield HEADER + len(raw).to_bytes(4, "big") + raw, self.pending.popleft()

    def oldest(self) -> float | None:
        """When the oldest request still waiting for its reply was sent."""
        return self.pending[0].sent_at if self.pending else None

    def forget(self, tab: Hashable) -> None:
        """A tab has gone: its replies are still read (the stream needs them) but go nowhere."""
        for entry in self.pending:
            entry.tabs = [t for t in entry.tabs if t != tab]

    def reset(self) -> list[Pending]:
        """The connection is gone: a fresh reply stream; returns what was still pending."""
        lost = list(self.pending)
        self.pending.clear()
        self._raw.clear()
        self._decoder = TelegramDecoder("reply", decode_data=self._decode_data)
        return lost
