"""The client's protocol core, without I/O: requests to bytes, received bytes to replies routed to their requests.

Rules:
- No socket, no clock, no asyncio here (like ``pltf.spec.codec``): the sync and asyncio clients own the I/O and
  call ``send`` / ``receive_data`` / ``connection_lost``; both behave the same because this file decides.
- Guide 6.1: the platform "returns data only on request". Only a request whose telegram has a reply layout
  (``TelegramDef.answered``: the GET_* requests) gets a ``PendingReply``; commands are fire and forget.
- A reply carries its request's identifier. Replies are matched to pending requests by identifier, first
  come first served per identifier, so replies to different requests in flight may arrive in any order.
- A reply nobody waits for any more (``abandon``, after a timeout) is dropped when it arrives, so a late
  reply can never answer a later request. A reply nobody asked for is kept in ``unsolicited`` (bounded).
- The first decode error poisons the connection (the stream is out of sync): every pending request fails
  with the same ``ProtocolError`` and nothing more can be sent.
"""

from __future__ import annotations

from collections import deque

from pltf.client.errors import ConnectionClosed, InvalidArgument, PlatformError, ProtocolError
from pltf.spec import errors as codec_errors
from pltf.spec.codec import DEFAULT_MAX_LENGTH, TelegramDecoder, encode
from pltf.spec.telegram import Telegram

MAX_UNSOLICITED = 100


class PendingReply:
    """A sent request that is answered (a GET_*): its reply, or the error that ended the wait.

    Attributes:
        request: the request telegram.
        seq: its sequence number on this connection (1 for the first telegram sent).
        reply: the reply telegram once it arrived, else None.
        error: the error that ended the wait (connection closed, protocol error), else None.
        abandoned: set when the caller gave up; the reply will be dropped when it arrives.
    """

    __slots__ = ("abandoned", "error", "reply", "request", "seq")

    def __init__(self, request: Telegram, seq: int) -> None:
        self.request = request
        self.seq = seq
        self.reply: Telegram | None = None
        self.error: PlatformError | None = None
        self.abandoned = False

    @property
    def done(self) -> bool:
        """True once the reply arrived or the wait ended with an error."""
        return self.reply is not None or self.error is not None

    def result(self) -> Telegram:
        """The reply telegram; raises the error that ended the wait, or RuntimeError if not done yet."""
        if self.error is not None:
            raise self.error
        if self.reply is None:
            raise RuntimeError(f"no reply to {self.request.NAME} yet")
        return self.reply

    def __repr__(self) -> str:
        state = "done" if self.done else "abandoned" if self.abandoned else "waiting"
        return f"<PendingReply #{self.seq} {self.request.NAME} {state}>"


class ClientCore:
    """One connection's protocol state: encoder, streaming reply decoder and the pending requests.

    Attributes:
        last_sent: telegram name -> sequence number of its last sending (the waits use it to know which
            command a state change should come from).
        unsolicited: replies that arrived with no request waiting for them (at most ``MAX_UNSOLICITED``).
    """

    def __init__(self, max_length: int = DEFAULT_MAX_LENGTH) -> None:
        self._decoder = TelegramDecoder("reply", max_length)
        self._pending: dict[int, deque[PendingReply]] = {}
        self._seq = 0
        self._closed: PlatformError | None = None
        self.last_sent: dict[str, int] = {}
        self.unsolicited: deque[Telegram] = deque(maxlen=MAX_UNSOLICITED)

    @property
    def closed(self) -> bool:
        """True after ``close``, ``connection_lost`` or a protocol error."""
        return self._closed is not None

    @property
    def seq(self) -> int:
        """Sequence number of the last telegram sent (0 before the first)."""
        return self._seq

    def send(self, telegram: Telegram) -> tuple[bytes, PendingReply | None]:
        """Encode a request: its frame, and a PendingReply when the platform answers it."""
        if self._closed is not None:
            raise ConnectionClosed(f"cannot send {telegram.NAME}: {self._closed}")
        if telegram.DIRECTION != "request":
            raise InvalidArgument(f"{telegram.NAME} is a {telegram.DIRECTION} telegram, not a request")
        try:
            frame = encode(telegram)
        except codec_errors.LocalProtocolError as exc:
            raise InvalidArgument(str(exc)) from exc
        self._seq += 1
        self.last_sent[telegram.NAME] = self._seq
        pending = None
        if telegram.DEF.answered:
            pending = PendingReply(telegram, self._seq)
            self._pending.setdefault(telegram.ID, deque()).append(pending)
        return frame, pending

    def abandon(self, pending: PendingReply) -> None:
        """Give up waiting: the reply is dropped when it comes (it must not answer a later request)."""
        pending.abandoned = True

    def receive_data(self, data: bytes) -> list[PendingReply]:
        """Feed received bytes (``b""`` = end of stream); returns the requests this completed.

        Raises ProtocolError (and closes the core) when the bytes break the protocol.
        """
        if self._closed is not None:
            return []
        if not data:
            return self.connection_lost("the platform closed the connection")
        self._decoder.receive_data(data)
        done: list[PendingReply] = []
        try:
            for reply in self._decoder:
                self._route(reply, done)
        except codec_errors.RemoteProtocolError as exc:
            error = ProtocolError(f"bad reply from the platform ({type(exc).__name__}): {exc}")
            error.__cause__ = exc
            done += self._fail_all(error)
            raise error from exc
        return done

    def connection_lost(self, reason: str = "connection lost") -> list[PendingReply]:
        """The transport is gone: every pending request fails with ConnectionClosed."""
        return self._fail_all(ConnectionClosed(reason))

    def close(self) -> list[PendingReply]:
        """Closed by the client: every pending request fails with ConnectionClosed."""
        return self._fail_all(ConnectionClosed("the connection was closed by the client"))

    def _route(self, reply: Telegram, done: list[PendingReply]) -> None:
        queue = self._pending.get(reply.ID)
        while queue:
            pending = queue.popleft()
            if pending.abandoned:
                return  # the late reply of a request that timed out: FIFO per id, so it is this one
            pending.reply = reply
            done.append(pending)
            return
        self.unsolicited.append(reply)

    def _fail_all(self, error: PlatformError) -> list[PendingReply]:
        if self._closed is None:
            self._closed = error
        failed: list[PendingReply] = []
        for queue in self._pending.values():
            for pending in queue:
                if not pending.abandoned and not pending.done:
                    pending.error = error
                    failed.append(pending)
            queue.clear()
        return failed
