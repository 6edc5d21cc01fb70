"""pltf.fake_hardware.serial_scanner: the S300-class telegram, its CRC, resynchronisation, and the pyserial links."""

from __future__ import annotations

import math
import os
import time

import pytest
import serial  # type: ignore[import-untyped]
from hypothesis import given
from hypothesis import strategies as st

from pltf.fake_hardware.serial_scanner import (
    POINTS,
    TELEGRAM_BYTES,
    S300Simulator,
    ScanDecoder,
    ScanReader,
    crc16,
    encode_telegram,
    open_serial_link,
)

RANGES = [float(500 + 10 * i) for i in range(POINTS)]


def decode_all(data: bytes, decoder: ScanDecoder | None = None) -> list[tuple[int, ...]]:
    d = decoder or ScanDecoder()
    d.receive_data(data)
    return [s.ranges_mm for s in d]


def test_crc_is_ccitt_false() -> None:
    assert crc16(b"123456789") == 0x29B1  # the catalogued check value of CRC-16/CCITT-FALSE


def test_telegram_layout() -> None:
    t = encode_telegram(RANGES, scan_number=0x01020304, telegram_number=0x0506)
    assert len(t) == TELEGRAM_BYTES == 1108
    assert t[:6] == b"\0" * 6 and int.from_bytes(t[6:8], "big") == (1108 - 4) // 2
    assert t[8:12] == b"\xff\x07\x02\x01" and t[12:14] == b"\0\0"
    assert t[14:18] == b"\x01\x02\x03\x04" and t[18:20] == b"\x05\x06"
    assert t[20:24] == b"\xbb\xbb\x11\x11"
    assert int.from_bytes(t[24:26], "little") == 50  # 500 mm = 50 cm
    assert int.from_bytes(t[-2:], "little") == crc16(t[4:-2])


def test_round_trip_and_scan_points() -> None:
    d = ScanDecoder()
    d.receive_data(encode_telegram([*RANGES[:-2], None, math.inf], 7, 9))
    (scan,) = list(d)
    assert (scan.scan_number, scan.telegram_number) == (7, 9)
    assert scan.ranges_mm[:-2] == tuple(round(r) for r in RANGES[:-2])
    assert scan.ranges_mm[-2:] == (81910, 81910)  # the 13-bit maximum
    x, y = scan.points()[0]
    assert math.atan2(y, x) == pytest.approx(math.radians(-135))
    assert math.hypot(x, y) == pytest.approx(500)


def test_byte_by_byte_with_garbage_around() -> None:
    stream = b"\x00\x00\xff\x07junk" + encode_telegram(RANGES, 1, 1) + b"\0\0\0" + encode_telegram(RANGES, 2, 2)
    d = ScanDecoder()
    got = []
    for i in range(len(stream)):
        d.receive_data(stream[i : i + 1])
        got += list(d)
    assert [s.telegram_number for s in got] == [1, 2]
    assert d.crc_errors == 0 and d.lost == 0


@given(index=st.integers(4, TELEGRAM_BYTES - 1), flip=st.integers(1, 255))
def test_a_corrupted_byte_is_never_accepted_and_the_next_telegram_is(index: int, flip: int) -> None:
    bad = bytearray(encode_telegram(RANGES, 1, 1))
    bad[index] ^= flip
    d = ScanDecoder()
    got = decode_all(bytes(bad) + encode_telegram(RANGES, 2, 2), d)
    assert got == [tuple(round(r) for r in RANGES)]
    assert d.lost == 0  # the first telegram seen is number 2


def test_lost_telegrams_are_counted_from_the_numbers() -> None:
    d = ScanDecoder()
    decode_all(encode_telegram(RANGES, 1, 1) + encode_telegram(RANGES, 4, 4), d)
    assert d.lost == 2 and d.telegrams == 2


def test_another_device_address_is_ignored() -> None:
    assert decode_all(encode_telegram(RANGES, 1, 1, address=8)) == []
    assert decode_all(encode_telegram(RANGES, 1, 1, address=8), ScanDecoder(address=8)) != []


def test_sim_url_is_a_pyserial_url_with_a_bounded_buffer() -> None:
    port = serial.serial_for_url("sim://?buffer=2000", timeout=0)
    try:
        assert port.write(b"x" * 1500) == 1500 and port.write(b"y" * 1000) == 500
        assert port.overruns == 1 and port.in_waiting == 2000
        assert port.read(10) == b"x" * 10
    finally:
        port.close()
    with pytest.raises(serial.SerialException):
        serial.serial_for_url("sim://?speed=3")


@pytest.mark.parametrize("url", ["sim://", "loop://"])
def test_simulator_and_reader_over_an_in_process_link(url: str) -> None:
    link = open_serial_link(url)
    try:
        assert link.device is not None
        sim = S300Simulator(link.device, lambda now: RANGES)
        reader = ScanReader(link.host)
        scans = []
        for k in range(11):
            sim.step(k * 0.02)
            scans += reader.poll(k * 0.02)
        assert [s.timestamp for s in scans] == pytest.approx([0.0, 0.04, 0.08, 0.12, 0.16, 0.2])
        assert not reader.silent(0.2) and reader.silent(0.33)
    finally:
        link.close()


def test_pty_link() -> None:
    link = open_serial_link("pty")
    try:
        assert link.device is not None
        S300Simulator(link.device, lambda now: RANGES).step(0.0)
        reader = ScanReader(link.host)
        deadline = time.monotonic() + 2.0  # the kernel moves pty data in wall-clock time
        scans = []
        while not scans and time.monotonic() < deadline:
            scans = reader.poll(0.0)
            time.sleep(0.001)
        assert len(scans) == 1 and scans[0].ranges_mm[0] == 500
    finally:
        link.close()


def test_a_real_port_has_no_simulated_device() -> None:
    master, slave = os.openpty()  # stands in for /dev/ttyUSB0: any path or URL that is not a loopback
    try:
        real = open_serial_link(os.ttyname(slave))
        assert real.device is None and real.host.is_open
        real.close()
    finally:
        os.close(master)
        os.close(slave)
