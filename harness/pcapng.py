"""Write recorded TCP exchanges as pcapng (synthetic Ethernet/IPv4/TCP framing of the real payloads).

Rules: one Section Header Block, one Ethernet interface, one Enhanced Packet Block per segment; each
conversation gets a handshake, its payloads with consistent sequence/ack numbers and valid checksums, and the
FINs that were seen, so Wireshark's "Follow TCP stream" shows the exchange. Only ``struct``, no I/O but the
final write.

Two ways in: ``write_pcapng`` writes whole recorded conversations at once (the fuzzer's findings);
``TcpFlow`` builds one conversation packet by packet as it happens, and ``file_header``/``enhanced_packet``
frame the blocks, for a writer that streams (the proxy's recordings, crafted segments in tests).
"""

from __future__ import annotations

import itertools
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

CLIENT_IP = bytes([127, 0, 0, 1])
SERVER_IP = bytes([127, 0, 0, 1])
CLIENT_MAC = bytes.fromhex("020000000001")
SERVER_MAC = bytes.fromhex("020000000002")
MSS = 65_000
SYN, ACK, PSH, FIN = 0x02, 0x10, 0x08, 0x01

Packet = tuple[float, bytes]  # (unix time, Ethernet frame)


@dataclass
class Conversation:
    client_port: int
    server_port: int
    events: list[tuple[float, str, bytes]] = field(default_factory=list)  # (unix time, "c2s"|"s2c", payload)
    client_fin: bool = False
    server_fin: bool = False


def _checksum(data: bytes) -> int:
    if len(data) % 2:
        data += b"\0"
    total = sum(struct.unpack(f"!{len(data) // 2}H", data))
    while total >> 16:
        total = (total & 0xFFFF) + (total >> 16)
    return int(~total & 0xFFFF)


def _packet(
    src_ip: bytes,
    dst_ip: bytes,
    sport: int,
    dport: int,
    seq: int,
    ack: int,
    flags: int,
    payload: bytes,
    ident: int,
    c2s: bool,
) -> bytes:
    tcp = struct.pack("!HHIIBBHHH", sport, dport, seq & 0xFFFFFFFF, ack & 0xFFFFFFFF, 5 << 4, flags, 65535, 0, 0)
    pseudo = src_ip + dst_ip + struct.pack("!BBH", 0, 6, len(tcp) + len(payload))
    csum = _checksum(pseudo + tcp + payload)
    tcp = tcp[:16] + struct.pack("!H", csum) + tcp[18:]
    total = 20 + len(tcp) + len(payload)
    ip = struct.pack("!BBHHHBBH4s4s", 0x45, 0, total, ident & 0xFFFF, 0x4000, 64, 6, 0, src_ip, dst_ip)
    ip = ip[:10] + struct.pack("!H", _checksum(ip)) + ip[12:]
    eth = (SERVER_MAC + CLIENT_MAC if c2s else CLIENT_MAC + SERVER_MAC) + b"\x08\x00"
    return eth + ip + tcp + payload


def _block(kind: int, body: bytes) -> bytes:
    body += b"\0" * (-len(body) % 4)
    n = 12 + len(body)
    return struct.pack("<II", kind, n) + body + struct.pack("<I", n)


def file_header() -> bytes:
    """The Section Header Block and the one Ethernet Interface Description Block every file starts with."""
    return _block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1)) + _block(1, struct.pack("<HHI", 1, 0, 0))


def enhanced_packet(t: float, pkt: bytes) -> bytes:
    """One Enhanced Packet Block (interface 0, microsecond time stamp)."""
    us = int(t * 1_000_000)
    return _block(6, struct.pack("<IIIII", 0, us >> 32, us & 0xFFFFFFFF, len(pkt), len(pkt)) + pkt)


class TcpFlow:
    """One TCP conversation built packet by packet: consistent sequence and ack numbers, payloads cut at MSS.

    ``ident`` numbers the IP datagrams; conversations written to one file share it.
    """

    def __init__(
        self,
        client_port: int,
        server_port: int,
        ident: Iterator[int] | None = None,
        *,
        client_ip: bytes = CLIENT_IP,
        server_ip: bytes = SERVER_IP,
    ) -> None:
        self.client = (client_ip, client_port)
        self.server = (server_ip, server_port)
        self.ident = ident if ident is not None else itertools.count(1)
        self.cseq, self.sseq = 1000, 5000

    def _emit(self, t: float, c2s: bool, flags: int, payload: bytes = b"") -> Packet:
        (src, sp), (dst, dp) = (self.client, self.server) if c2s else (self.server, self.client)
        seq, ack = (self.cseq, self.sseq) if c2s else (self.sseq, self.cseq)
        pkt = _packet(src, dst, sp, dp, seq, ack, flags, payload, next(self.ident), c2s)
        step = len(payload) + (1 if flags & (SYN | FIN) else 0)
        if c2s:
            self.cseq += step
        else:
            self.sseq += step
        return t, pkt

    def handshake(self, t: float) -> list[Packet]:
        return [self._emit(t, True, SYN), self._emit(t, False, SYN | ACK), self._emit(t, True, ACK)]

    def data(self, t: float, c2s: bool, payload: bytes) -> list[Packet]:
        """The payload as one segment, or several of at most MSS bytes."""
        return [self._emit(t, c2s, PSH | ACK, payload[k : k + MSS]) for k in range(0, len(payload), MSS)]

    def fin(self, t: float, c2s: bool) -> list[Packet]:
        return [self._emit(t, c2s, FIN | ACK)]


def _conversation(conv: Conversation, ident: Iterator[int]) -> list[Packet]:
    t0 = conv.events[0][0] if conv.events else 0.0
    flow = TcpFlow(conv.client_port, conv.server_port, ident)
    out = flow.handshake(t0)
    last = t0
    for t, direction, payload in conv.events:
        last = t
        out += flow.data(t, direction == "c2s", payload)
    if conv.client_fin:
        out += flow.fin(last, True)
    if conv.server_fin:
        out += flow.fin(last, False)
    return out


def write_pcapng(path: Path, conversations: list[Conversation]) -> None:
    ident = itertools.count(1)
    packets: list[Packet] = []
    for conv in conversations:
        packets.extend(_conversation(conv, ident))
    packets.sort(key=lambda p: p[0])
    path.write_bytes(file_header() + b"".join(enhanced_packet(t, pkt) for t, pkt in packets))
