"""An MCAP writer for the export's message rate (issue 35): chunked, indexed, compressed with zstd, lz4 or nothing.

The ``mcap`` library's ``Writer`` costs ~5 us of Python per message (a ``Message`` dataclass, a ``BytesIO`` write
per field, a size placeholder sought back to, an index tuple) and compresses its chunks with zstd at
python-zstandard's default level 3 (it takes no level). For an hour of 20 Hz status polling (360,000 messages,
~810 MB) that was 1.7 s of writing and 3.5 s of zstd out of the export's 14.3 s. Here a message is one
``struct.pack`` of its 31-byte head and two list appends, and the chunk's compressor is chosen (``COMPRESSIONS``).

The file is what the MCAP specification (mcap.dev/spec, "Records") describes and the library writes: magic,
Header, the Schema and Channel records (in the data section before the first chunk), Chunk records each followed
by its MessageIndex records (one per channel in the chunk: log time and offset of each of its messages), DataEnd,
and the summary section (schemas and channels repeated, Statistics, ChunkIndex records, empty attachment and
metadata index groups), SummaryOffset records, Footer, magic. CRCs: each chunk's uncompressed CRC and the
summary's; the data section's CRC is 0 ("not available", as the library writes it by default). The summary's
records are the library's own (``mcap.records``), so only the Message and MessageIndex records are written here.

Compression per chunk (the spec's ``compression`` field): ``zstd`` (python-zstandard, level ``ZSTD_LEVEL``),
``lz4`` (the LZ4 frame format, python-lz4, as the library writes it), or ``""`` (none). Foxglove, @mcap/core with
its decompress handlers and the Python ``mcap`` reader read all three.
"""

from __future__ import annotations

import struct
import sys
import zlib
from array import array
from collections.abc import Callable
from typing import IO

import lz4.frame  # type: ignore[import-untyped]  # python-lz4 has no annotations
import zstandard
from mcap.data_stream import RecordBuilder
from mcap.records import (
    Channel,
    Chunk,
    ChunkIndex,
    DataEnd,
    Footer,
    Header,
    Schema,
    Statistics,
    SummaryOffset,
)

MAGIC = b"\x89MCAP0\r\n"
MESSAGE, MESSAGE_INDEX = 0x05, 0x07  # opcodes (spec "Records")
SCHEMA, CHANNEL, STATISTICS, CHUNK_INDEX, ATTACHMENT_INDEX, METADATA_INDEX = 0x03, 0x04, 0x0B, 0x08, 0x0A, 0x0D
FOOTER = 0x02
_MESSAGE_HEAD = struct.Struct("<BQHIQQ")  # opcode, record length, channel id, sequence, log time, publish time
_INDEX_HEAD = struct.Struct("<BQHI")  # opcode, record length, channel id, byte length of the (time, offset) pairs
HEAD = _MESSAGE_HEAD.size  # 31 bytes before a message's data
ZSTD_LEVEL = 1  # an hour: level 1 ~1.5 s for 331 MB, level 3 (the library's) ~3.0 s for 287 MB (mcap.md)
CHUNK_BYTES = 4 * 1024 * 1024  # uncompressed bytes of a chunk (the library's default is 1 MiB)


def _zstd() -> Callable[[bytes], bytes]:
    return zstandard.ZstdCompressor(level=ZSTD_LEVEL).compress


def _lz4() -> Callable[[bytes], bytes]:
    return lz4.frame.compress  # type: ignore[no-any-return]


def _none() -> Callable[[bytes], bytes]:
    return bytes


COMPRESSIONS: dict[str, tuple[str, Callable[[], Callable[[bytes], bytes]]]] = {  # option: (chunk field, compressor)
    "zstd": ("zstd", _zstd),
    "lz4": ("lz4", _lz4),
    "none": ("", _none),
}


def _pairs(values: array) -> bytes:  # type: ignore[type-arg]
    """uint64 values little-endian, as MCAP writes every integer."""
    if sys.byteorder != "little":
        values = array("Q", values)
        values.byteswap()
    return values.tobytes()


def _end(builder: RecordBuilder) -> bytes:
    """The builder's records, taken out (it starts empty again)."""
    return builder.end()  # type: ignore[no-untyped-call,no-any-return]  # mcap 1.6: end() is not annotated


class McapWriter:
    """Writes an MCAP file to ``stream`` (binary; its ``tell`` is not used, so any stream will do): ``start``,
    ``register_schema`` and ``register_channel`` before the first message, ``add`` for each message, ``finish``
    (the stream stays open). ``compression``: a key of COMPRESSIONS."""

    def __init__(self, stream: IO[bytes], compression: str = "zstd", chunk_size: int = CHUNK_BYTES) -> None:
        self._stream = stream
        self._field, make = COMPRESSIONS[compression]
        self._compress = make()
        self._chunk_size = chunk_size
        self._at = 0  # bytes written to the stream
        self._schemas: list[Schema] = []
        self._channels: list[Channel] = []
        self._parts: list[bytes] = []  # the chunk's records
        self._size = 0  # their bytes
        self._index: dict[int, array] = {}  # type: ignore[type-arg]  # channel: log time, offset, log time, ...
        self._chunk_indexes: list[ChunkIndex] = []
        self._counts: dict[int, int] = {}
        self._times: list[int] = []  # each chunk's first and last log time

    def _write(self, data: bytes) -> None:
        self._stream.write(data)
        self._at += len(data)

    def _records(self, *records: Header | Schema | Channel | DataEnd) -> None:
        builder = RecordBuilder()
        for rec in records:
            rec.write(builder)
        self._write(_end(builder))

    def start(self, profile: str = "", library: str = "pltf") -> None:
        self._write(MAGIC)
        self._records(Header(profile=profile, library=library))

    def register_schema(self, name: str, encoding: str, data: bytes) -> int:
        schema = Schema(id=len(self._schemas) + 1, name=name, encoding=encoding, data=data)
        self._schemas.append(schema)
        self._records(schema)
        return schema.id

    def register_channel(self, topic: str, message_encoding: str, schema_id: int) -> int:
        channel = Channel(
            id=len(self._channels) + 1, topic=topic, message_encoding=message_encoding, schema_id=schema_id, metadata={}
        )
        self._channels.append(channel)
        self._index[channel.id] = array("Q")
        self._counts[channel.id] = 0
        self._records(channel)
        return channel.id

    def add(self, channel: int, log_time: int, data: bytes, publish_time: int, sequence: int) -> None:
        """One message (times in ns since the epoch, both >= 0)."""
        index = self._index[channel]
        index.append(log_time)
        index.append(self._size)
        self._parts.append(_MESSAGE_HEAD.pack(MESSAGE, len(data) + 22, channel, sequence, log_time, publish_time))
        self._parts.append(data)
        self._size += HEAD + len(data)
        if self._size > self._chunk_size:
            self._finish_chunk()

    def _finish_chunk(self) -> None:
        if not self._parts:
            return
        data = b"".join(self._parts)
        times = [t for index in self._index.values() if index for t in (min(index[::2]), max(index[::2]))]
        first, last = min(times), max(times)
        self._times += [first, last]
        packed = self._compress(data)
        chunk = Chunk(
            message_start_time=first,
            message_end_time=last,
            uncompressed_size=len(data),
            uncompressed_crc=zlib.crc32(data),
            compression=self._field,
            data=packed,
        )
        builder = RecordBuilder()
        chunk.write(builder)
        start, record = self._at, _end(builder)
        self._write(record)
        offsets: dict[int, int] = {}
        indexes: list[bytes] = []
        for channel, index in self._index.items():
            if not index:
                continue
            offsets[channel] = self._at + sum(map(len, indexes))
            body = _pairs(index)
            indexes.append(_INDEX_HEAD.pack(MESSAGE_INDEX, 6 + len(body), channel, len(body)) + body)
            self._counts[channel] += len(index) // 2
            self._index[channel] = array("Q")
        self._write(b"".join(indexes))
        self._chunk_indexes.append(
            ChunkIndex(
                message_start_time=first,
                message_end_time=last,
                chunk_start_offset=start,
                chunk_length=len(record),
                message_index_offsets=offsets,
                message_index_length=sum(map(len, indexes)),
                compression=self._field,
                compressed_size=len(packed),
                uncompressed_size=len(data),
            )
        )
        self._parts, self._size = [], 0

    def finish(self) -> None:
        """The last chunk, DataEnd, the summary section, its offsets and the footer."""
        self._finish_chunk()
        self._records(DataEnd(data_section_crc=0))
        start = self._at
        counts = {c: n for c, n in self._counts.items() if n}
        stats = Statistics(
            message_count=sum(counts.values()),
            schema_count=len(self._schemas),
            channel_count=len(self._channels),
            attachment_count=0,
            metadata_count=0,
            chunk_count=len(self._chunk_indexes),
            message_start_time=min(self._times, default=0),
            message_end_time=max(self._times, default=0),
            channel_message_counts=counts,
        )
        groups: list[tuple[int, list[Schema] | list[Channel] | list[Statistics] | list[ChunkIndex]]] = [
            (SCHEMA, self._schemas),
            (CHANNEL, self._channels),
            (STATISTICS, [stats]),
            (CHUNK_INDEX, self._chunk_indexes),
            (ATTACHMENT_INDEX, []),
            (METADATA_INDEX, []),
        ]
        summary = RecordBuilder()
        offsets = []
        for opcode, records in groups:
            at = summary.count
            for rec in records:
                rec.write(summary)
            offsets.append(SummaryOffset(group_opcode=opcode, group_start=start + at, group_length=summary.count - at))
        offset_start = start + summary.count
        for offset in offsets:
            offset.write(summary)
        data = _end(summary)
        crc = zlib.crc32(struct.pack("<BQQQ", FOOTER, 20, start, offset_start), zlib.crc32(data))
        self._write(data)
        footer = RecordBuilder()
        Footer(summary_start=start, summary_offset_start=offset_start, summary_crc=crc).write(footer)
        self._write(_end(footer) + MAGIC)
