"""A SICK S300-class laser scanner on a serial line: the simulated device, the telegram codec and the reader.

Rules (erratum E-HW-015):
- Telegram of the S300's continuous data output (protocol 02.01) as public drivers read it: 4 zero bytes, then
  a 16-bit word count (big-endian) of everything after those 4 bytes, 0xFF, the device address (7), protocol
  02 01, status, scan number (u32), telegram number (u16), block id BB BB, field id 11 11, 541 distances
  (u16 little-endian: bits 0-12 distance in cm, 13 reflector, 14 protective field, 15 warning field) and a
  CRC-16/CCITT (poly 0x1021, initial 0xFFFF) of the bytes after the 4 zero bytes, sent low byte first.
- 270 degrees from -135 to +135 degrees in 0.5-degree steps, one telegram per 40 ms of simulated time.
- ``ScanDecoder`` is sans-IO (bytes in, scans out): it resynchronises on the header, skips a header whose size
  is beyond the longest S300 telegram (it never waits for a corrupt length), rejects a telegram whose CRC is
  wrong (``crc_errors``) and counts telegrams it never saw from gaps in the telegram number (``lost``).
- ``S300Simulator`` writes to anything with ``write(bytes)`` in ``step(now)``; ``ScanReader`` polls a pyserial
  port without blocking (``timeout=0``). ``open_serial_link`` gives both ends for ``sim://`` (the default: an
  in-memory pyserial loopback, ``fake_hardware/protocol_sim.py``, deterministic in simulated time), ``loop://``
  (pyserial's own: slow, blocks when 4 KiB are unread), a pty pair (``"pty"``: real file descriptors, but the
  kernel delivers in wall-clock time, so only for a server paced in real time), or only the reading end for a
  real port URL.
"""

from __future__ import annotations

import binascii
import math
import os
import random
import struct
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import NamedTuple, Protocol

import numpy as np
import numpy.typing as npt
import serial  # type: ignore[import-untyped]  # no stubs; types-pyserial is not a dependency

if "pltf.fake_hardware" not in serial.protocol_handler_packages:
    serial.protocol_handler_packages.append("pltf.fake_hardware")  # sim:// (fake_hardware/protocol_sim.py)

POINTS = 541
START_ANGLE = math.radians(-135.0)
ANGLE_STEP = math.radians(0.5)
PERIOD = 0.04  # s
ADDRESS = 7
MAX_CM = 0x1FFF
_HEAD = struct.Struct(">4xHHBBBBHIH")  # zeros, trigger, size, 0xFF, address, protocol (2 bytes), status, scan, tel
_ZEROS = b"\0" * 6
_BLOCK = b"\xbb\xbb\x11\x11"
TELEGRAM_BYTES = _HEAD.size + len(_BLOCK) + 2 * POINTS + 2  # 1108: the longest telegram (270 degrees)
MIN_TELEGRAM = _HEAD.size + 2

Ranges = Sequence[float | None] | npt.NDArray[np.float64]  # mm; None, inf or NaN: no echo
RangeSource = Callable[[float], Ranges]


_NO_ECHO = struct.pack(f"<{POINTS}H", *([MAX_CM] * POINTS))


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE, the S300's telegram checksum."""
    return binascii.crc_hqx(data, 0xFFFF)


class Scan(NamedTuple):
    timestamp: float  # simulated s at which the reader got the whole telegram
    scan_number: int
    telegram_number: int
    ranges_mm: tuple[int, ...]  # 541 distances, 10 mm resolution
    flags: tuple[int, ...]  # bits 13-15 of each value (reflector, protective field, warning field)

    def points(self) -> list[tuple[float, float]]:
        """The scan in the scanner's frame, mm (x forward); zero ranges (no measurement) are left out."""
        return [
            (r * math.cos(START_ANGLE + i * ANGLE_STEP), r * math.sin(START_ANGLE + i * ANGLE_STEP))
            for i, r in enumerate(self.ranges_mm)
            if r > 0
        ]


def encode_telegram(ranges_mm: Ranges, scan_number: int, telegram_number: int, address: int = ADDRESS) -> bytes:
    """One distance telegram; a range of None, inf or beyond the 13-bit maximum reads as the maximum."""
    size = (TELEGRAM_BYTES - 4) // 2
    head = _HEAD.pack(0, size, 0xFF, address, 2, 1, 0, scan_number & 0xFFFFFFFF, telegram_number & 0xFFFF)
    body = head[4:] + _BLOCK + _distances(ranges_mm)
    return head[:4] + body + struct.pack("<H", crc16(body))


def _distances(ranges_mm: Ranges) -> bytes:
    """The 541 distance words (cm, little-endian), vectorised: None and NaN become the maximum."""
    n = len(ranges_mm)
    if n == 0 or (ranges_mm[0] is None and list(ranges_mm).count(None) == n):
        return _NO_ECHO
    a = np.full(POINTS, np.inf)
    a[: min(n, POINTS)] = np.asarray(ranges_mm[:POINTS], dtype=float)  # None -> NaN
    cm = np.rint(a / 10.0)
    np.clip(cm, 0, MAX_CM, out=cm)
    cm[~np.isfinite(a)] = MAX_CM
    return cm.astype("<u2").tobytes()


class ScanDecoder:
    def __init__(self, address: int = ADDRESS) -> None:
        self.address = address
        self.telegrams = 0
        self.crc_errors = 0
        self.lost = 0
        self.discarded = 0  # bytes skipped while searching a header
        self._buf = bytearray()
        self._scans: list[Scan] = []
        self._last_number: int | None = None

    def receive_data(self, data: bytes) -> None:
        self._buf += data
        self._parse()

    def __iter__(self) -> Iterator[Scan]:
        scans, self._scans = self._scans, []
        return iter(scans)

    def _skip(self, n: int) -> None:
        del self._buf[:n]
        self.discarded += n

    def _parse(self) -> None:
        buf = self._buf
        while True:
            i = buf.find(_ZEROS)
            if i < 0:
                self._skip(max(0, len(buf) - len(_ZEROS) + 1))
                return
            if i:
                self._skip(i)
            if len(buf) < _HEAD.size:
                return
            _, size, flag, address, proto, minor, _, scan, number = _HEAD.unpack_from(buf)
            total = 4 + 2 * size
            header_ok = (flag, address, minor) == (0xFF, self.address, 1) and proto in (2, 3)
            if not header_ok or not MIN_TELEGRAM <= total <= TELEGRAM_BYTES:  # never wait for a corrupt size
                self._skip(1)
                continue
            if len(buf) < total:
                return
            if crc16(bytes(buf[4 : total - 2])) != buf[total - 2] | buf[total - 1] << 8:
                self.crc_errors += 1
                self._skip(1)
                continue
            self._accept(bytes(buf[:total]), scan, number)
            del buf[:total]

    def _accept(self, telegram: bytes, scan: int, number: int) -> None:
        if telegram[_HEAD.size : _HEAD.size + 4] != _BLOCK:
            return  # an I/O or reflector telegram: not a distance scan
        raw = np.frombuffer(telegram, "<u2", POINTS, _HEAD.size + 4)
        if self._last_number is not None:
            self.lost += (number - self._last_number - 1) & 0xFFFF
        self._last_number = number
        self.telegrams += 1
        ranges = tuple(((raw & MAX_CM).astype(np.int32) * 10).tolist())
        self._scans.append(Scan(0.0, scan, number, ranges, tuple((raw >> 13).tolist())))


class Writable(Protocol):
    def write(self, data: bytes, /) -> int | None: ...


class S300Simulator:
    """The scanner: a telegram every ``period`` of simulated time, ranges from ``range_source(now)`` (mm)."""

    def __init__(
        self,
        port: Writable,
        range_source: RangeSource | None = None,
        address: int = ADDRESS,
        period: float = PERIOD,
        rng: random.Random | None = None,
    ) -> None:
        self.port = port
        self.range_source = range_source
        self.address = address
        self.period = period
        self.rng = rng or random.Random(0)
        self.corrupt_probability = 0.0  # fault: each telegram gets one byte flipped with this probability
        self.silent = False  # fault: the scanner sends nothing
        self.sent = 0
        self.corrupted = 0
        self._scan = 0
        self._next: float | None = None

    def step(self, now: float) -> None:
        if self._next is None:
            self._next = now
        if now < self._next - 1e-9:
            return
        self._next += self.period
        if self._next <= now:
            self._next = now + self.period
        if self.silent:
            return
        ranges = self.range_source(now) if self.range_source else [None] * POINTS
        telegram = bytearray(encode_telegram(ranges, self._scan, self.sent, self.address))
        self._scan += 1
        if self.corrupt_probability > 0.0 and self.rng.random() < self.corrupt_probability:
            telegram[self.rng.randrange(4, len(telegram))] ^= self.rng.randrange(1, 256)
            self.corrupted += 1
        self.sent += 1
        self.port.write(bytes(telegram))


class ScanReader:
    """The controller's end: reads what the port has, decodes, and notices when the scanner falls silent."""

    def __init__(self, port: serial.SerialBase, decoder: ScanDecoder | None = None, timeout: float = 3 * PERIOD):
        self.port = port
        self.decoder = decoder or ScanDecoder()
        self.timeout = timeout
        self.last_scan: Scan | None = None
        self._since: float | None = None

    def poll(self, now: float) -> list[Scan]:
        if self._since is None:
            self._since = now
        waiting = self.port.in_waiting
        if waiting:
            self.decoder.receive_data(self.port.read(waiting))
        scans = [s._replace(timestamp=now) for s in self.decoder]
        if scans:
            self.last_scan = scans[-1]
        return scans

    def silent(self, now: float) -> bool:
        """No valid telegram for ``timeout`` simulated seconds."""
        last = self.last_scan.timestamp if self.last_scan else self._since
        return last is not None and now - last > self.timeout


class _PtyMaster:
    """The device end of a pty pair: non-blocking writes; what does not fit is lost like on a real line."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.overruns = 0

    def write(self, data: bytes, /) -> int:
        try:
            n = os.write(self.fd, data)
        except BlockingIOError:
            n = 0
        if n < len(data):
            self.overruns += 1
        return n


@dataclass
class SerialLink:
    host: serial.SerialBase  # the controller's end, read with ScanReader
    device: Writable | None  # the simulated scanner's end; None on a real port (a real scanner sends)
    _fds: tuple[int, ...] = ()

    def close(self) -> None:
        self.host.close()
        for fd in self._fds:
            os.close(fd)


def open_serial_link(url: str = "sim://", baudrate: int = 500_000) -> SerialLink:
    """``sim://`` or ``loop://`` (one pyserial object, both ends), ``pty`` (a pty pair: pyserial on the slave),
    or any pyserial URL / device path of a real scanner (reading end only)."""
    if url == "pty":
        master, slave = os.openpty()
        os.set_blocking(master, False)
        host = serial.Serial(os.ttyname(slave), baudrate=baudrate, timeout=0)
        return SerialLink(host, _PtyMaster(master), (master, slave))
    port = serial.serial_for_url(url, baudrate=baudrate, timeout=0)
    return SerialLink(port, port if url.startswith(("sim://", "loop://")) else None)
