"""The sans-IO codec: telegram objects <-> bytes on the wire.

Rules:
- Framing (guide 6.2 figure 11, confirmed by the captures in field-evidence.md): the header FF 01 FE 02,
  a big-endian uint32 N counting the data bytes only, then N data bytes whose first byte is the telegram
  identifier. Replies are framed like requests (erratum E-WIRE-001).
- ``TelegramDecoder`` yields the same telegrams however the byte stream is split or coalesced. A frame's
  length is checked against ``max_length`` before anything is buffered for it.
- After an error the decoder is poisoned: the connection is no longer in sync and must be closed.
- Nothing here touches a socket or a clock.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable, Iterator, Mapping
from typing import Any, TypeVar

from pltf.spec import errors
from pltf.spec.compiler import Decoder, Encoder, compile_telegram
from pltf.spec.model import Direction, TelegramDef, load_telegrams
from pltf.spec.telegram import Telegram

HEADER = b"\xff\x01\xfe\x02"
_FRAME_HEAD = struct.Struct(">4sI")
FRAME_OVERHEAD = _FRAME_HEAD.size  # header + length field
# Erratum E-WIRE-004: the guide sets no maximum; 16 MiB holds any map a platform can use.
DEFAULT_MAX_LENGTH = 16 * 1024 * 1024

K = TypeVar("K", int, str)
_Compiled = tuple[type[Telegram], Decoder, Encoder]


class _Classes(Mapping[K, type[Telegram]]):
    """A TelegramSet's classes by id or by name: the keys are known at once, a class is compiled when looked up."""

    def __init__(self, owner: TelegramSet, defs: dict[K, TelegramDef]) -> None:
        self._owner = owner
        self._defs: dict[K, TelegramDef] = defs

    def __getitem__(self, key: K) -> type[Telegram]:
        return self._owner._compiled(self._defs[key])[0]

    def __contains__(self, key: object) -> bool:
        return key in self._defs

    def __iter__(self) -> Iterator[K]:
        return iter(self._defs)

    def __len__(self) -> int:
        return len(self._defs)


class TelegramSet:
    """All telegram classes of one direction, by name (attribute or ``[]``) and by id.

    A telegram's class, decoder and encoder are compiled the first time it is used (looked up by id or name,
    decoded, or met while iterating): a process that decodes a few frames compiles a few telegrams, not all 93
    (compiling them all took ~80 ms of the client's ~570 ms import, issue 18). Two threads that
    compile the same telegram at once both get the one class that ``setdefault`` kept.
    """

    def __init__(self, direction: Direction, tdefs: Iterable[TelegramDef] = ()) -> None:
        self.direction = direction
        self._defs: dict[int, TelegramDef] = {}
        self._names: dict[str, TelegramDef] = {}
        self._done: dict[int, _Compiled] = {}
        self._decoders: list[Decoder | None] = [None] * 256
        self._encoders: dict[type[Telegram], Encoder] = {}
        self.by_id: Mapping[int, type[Telegram]] = _Classes(self, self._defs)
        self.by_name: Mapping[str, type[Telegram]] = _Classes(self, self._names)
        for tdef in tdefs:
            self._add(tdef)

    def _add(self, tdef: TelegramDef) -> None:
        self._defs[tdef.id] = tdef
        for name in (tdef.name, *tdef.aliases):
            self._names[name] = tdef

    def _compiled(self, tdef: TelegramDef) -> _Compiled:
        done = self._done.get(tdef.id)
        if done is None:
            mine = compile_telegram(tdef, self.direction)
            self._encoders[mine[0]] = mine[2]  # before it is published: whoever gets the class can encode it
            done = self._done.setdefault(tdef.id, mine)
            self._decoders[tdef.id] = done[1]
        return done

    def __getattr__(self, name: str) -> type[Telegram]:
        try:
            return self.__dict__["by_name"][name]  # type: ignore[no-any-return]
        except KeyError:
            raise AttributeError(name) from None

    def __getitem__(self, name: str) -> type[Telegram]:
        return self.by_name[name]

    def __iter__(self) -> Iterator[type[Telegram]]:
        return iter(self.by_id.values())

    def __len__(self) -> int:
        return len(self._defs)

    def decode_data(self, data: bytes) -> Telegram:
        """Decode one telegram's data (identifier first, no header or length)."""
        if not data:
            raise errors.UnknownTelegram("empty telegram: no identifier byte")
        dec = self._decoders[data[0]]
        if dec is None:
            tdef = self._defs.get(data[0])
            if tdef is None:
                raise errors.UnknownTelegram(f"unknown {self.direction} identifier {data[0]}")
            dec = self._compiled(tdef)[1]
        return dec(data)

    def encode_data(self, telegram: Telegram) -> bytes:
        enc = self._encoders.get(type(telegram))
        if enc is None:
            raise errors.FieldValueError(f"{telegram!r} is not a {self.direction} telegram")
        return enc(telegram)


def _build() -> dict[Direction, TelegramSet]:
    tdefs = load_telegrams()
    return {
        "request": TelegramSet("request", tdefs),
        "reply": TelegramSet("reply", (t for t in tdefs if t.reply is not None or not t.layout_known)),
    }


_SETS = _build()
REQUESTS: TelegramSet = _SETS["request"]
REPLIES: TelegramSet = _SETS["reply"]


def telegram_set(direction: Direction) -> TelegramSet:
    return _SETS[direction]


def frame(data: bytes) -> bytes:
    """Wrap telegram data in header and length (guide 6.2)."""
    return _FRAME_HEAD.pack(HEADER, len(data)) + data


def encode(telegram: Telegram) -> bytes:
    """The whole frame of a telegram (its direction is part of its type)."""
    return frame(_SETS[telegram.DIRECTION].encode_data(telegram))


def build(direction: Direction, name: str, /, **fields: Any) -> Telegram:
    """Construct a telegram by name; unknown or missing fields raise FieldValueError."""
    try:
        cls = _SETS[direction].by_name[name]
    except KeyError:
        raise errors.FieldValueError(f"no {direction} telegram named {name!r}") from None
    wanted = set(cls._fields)
    if set(fields) != wanted:
        missing, extra = sorted(wanted - set(fields)), sorted(set(fields) - wanted)
        raise errors.FieldValueError(f"{name}: missing fields {missing}, unknown fields {extra}")
    return cls(**fields)


def decode_frame(data: bytes, direction: Direction, max_length: int = DEFAULT_MAX_LENGTH) -> Telegram:
    """Decode exactly one frame; anything before, after or missing is an error."""
    if len(data) >= FRAME_OVERHEAD:  # fast path for a well-formed frame; anything irregular takes the slow one
        head, length = _FRAME_HEAD.unpack_from(data)
        if head == HEADER and length <= max_length and len(data) == FRAME_OVERHEAD + length:
            return _SETS[direction].decode_data(bytes(data[FRAME_OVERHEAD:]))
    dec = TelegramDecoder(direction, max_length)
    dec.receive_data(data)
    telegram = dec.next_telegram()
    if telegram is None:
        dec.receive_data(b"")
        dec.next_telegram()  # raises Truncated
        raise errors.Truncated("no complete frame")  # pragma: no cover - next_telegram raised
    if dec.pending:
        raise errors.TrailingBytes(f"{dec.pending} bytes after the frame of {telegram.NAME}")
    return telegram


class TelegramDecoder:
    """Streaming decoder: feed bytes with ``receive_data``, take telegrams with ``next_telegram``.

    ``receive_data(b"")`` marks the end of the stream; a partial frame then raises Truncated.
    """

    def __init__(
        self,
        direction: Direction,
        max_length: int = DEFAULT_MAX_LENGTH,
        decode_data: Callable[[bytes], Telegram] | None = None,
    ) -> None:
        self._set = _SETS[direction]
        # decode_data: one telegram's data (identifier first) -> the telegram; a caller may memoize it
        self._decode_data = decode_data or self._set.decode_data
        self.direction = direction
        self.max_length = max_length
        self._buf = bytearray()
        self._pos = 0
        self._eof = False
        self._error: errors.RemoteProtocolError | None = None

    @property
    def pending(self) -> int:
        """Bytes received and not yet consumed by a telegram."""
        return len(self._buf) - self._pos

    def receive_data(self, data: bytes) -> None:
        if self._eof and data:
            raise errors.LocalProtocolError("receive_data after end of stream")
        if not data:
            self._eof = True
            return
        if self._pos and self._pos >= len(self._buf) // 2:
            del self._buf[: self._pos]
            self._pos = 0
        self._buf += data

    def next_telegram(self) -> Telegram | None:
        """The next complete telegram, or None when more data is needed."""
        if self._error is not None:
            raise self._error
        try:
            return self._next()
        except errors.RemoteProtocolError as exc:
            self._error = exc
            raise

    def __iter__(self) -> Iterator[Telegram]:
        while (t := self.next_telegram()) is not None:
            yield t

    def _next(self) -> Telegram | None:
        buf, pos = self._buf, self._pos
        avail = len(buf) - pos
        if avail < FRAME_OVERHEAD:
            if avail and not HEADER.startswith(bytes(buf[pos : pos + min(avail, 4)])):
                raise errors.BadHeader(f"bad header {bytes(buf[pos : pos + 4]).hex()} (expected ff01fe02)")
            if self._eof and avail:
                raise errors.Truncated(f"stream ended inside a frame header ({avail} bytes)")
            return None
        head, length = _FRAME_HEAD.unpack_from(buf, pos)
        if head != HEADER:
            raise errors.BadHeader(f"bad header {head.hex()} (expected ff01fe02)")
        if length > self.max_length:
            raise errors.FrameTooLarge(f"frame length {length} over the maximum {self.max_length}")
        end = pos + FRAME_OVERHEAD + length
        if end > len(buf):
            if self._eof:
                raise errors.Truncated(f"stream ended inside a frame: {len(buf) - pos} of {end - pos} bytes")
            return None
        data = bytes(buf[pos + FRAME_OVERHEAD : end])
        self._pos = end
        return self._decode_data(data)
