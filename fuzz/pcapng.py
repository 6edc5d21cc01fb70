"""Write recorded TCP exchanges as pcapng (synthetic Ethernet/IPv4/TCP framing of the real payloads).

Rules: one Section Header Block, one Ethernet interface, one Enhanced Packet Block per segment; each
conversation gets a handshake, its payloads with consistent sequence/ack numbers and valid checksums, and the
FINs that were seen, so Wireshark's "Follow TCP stream" shows the exchange. Only ``struct``, no I/O but the
final write.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

CLIENT_IP = bytes([127, 0, 0, 1])
SERVER_IP = bytes([127, 0, 0, 1])
CLIENT_MAC = bytes.fromhex("020000000001")
SERVER_MAC = bytes.fromhex("020000000002")
MSS = 65_000
SYN, ACK, PSH, FIN = 0x02, 0x10, 0x08, 0x01


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


def _packet(src_ip: bytes, dst_ip: bytes, sport: int, dport: int, seq: int, ack: int, flags: int, payload: bytes,
            ident: int, c2s: bool) -> bytes:  # fmt: skip
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


def _epb(t: float, pkt: bytes) -> bytes:
    us = int(t * 1_000_000)
    return _block(6, struct.pack("<IIIII", 0, us >> 32, us & 0xFFFFFFFF, len(pkt), len(pkt)) + pkt)


def _conversation(conv: Conversation, ident: list[int]) -> list[tuple[float, bytes]]:
    out: list[tuple[float, bytes]] = []
    t0 = conv.events[0][0] if conv.events else 0.0
    cseq, sseq = 1000, 5000
    c, s = (CLIENT_IP, conv.client_port), (SERVER_IP, conv.server_port)

    def emit(t: float, c2s: bool, flags: int, payload: bytes = b"") -> None:
        nonlocal cseq, sseq
        ident[0] += 1
        (src, sp), (dst, dp) = (c, s) if c2s else (s, c)
        seq, ack = (cseq, sseq) if c2s else (sseq, cseq)
        out.append((t, _packet(src, dst, sp, dp, seq, ack, flags, payload, ident[0], c2s)))
        step = len(payload) + (1 if flags & (SYN | FIN) else 0)
        if c2s:
            cseq += step
        else:
            sseq += step

    emit(t0, True, SYN)
    emit(t0, False, SYN | ACK)
    emit(t0, True, ACK)
    last = t0
    for t, direction, payload in conv.events:
        last = t
        for k in range(0, len(payload), MSS):
            emit(t, direction == "c2s", PSH | ACK, payload[k : k + MSS])
    if conv.client_fin:
        emit(last, True, FIN | ACK)
    if conv.server_fin:
        emit(last, False, FIN | ACK)
    return out


def write_pcapng(path: Path, conversations: list[Conversation]) -> None:
    shb = _block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1))
    idb = _block(1, struct.pack("<HHI", 1, 0, 0))
    ident = [0]
    packets: list[tuple[float, bytes]] = []
    for conv in conversations:
        packets.extend(_conversation(conv, ident))
    packets.sort(key=lambda p: p[0])
    path.write_bytes(shb + idb + b"".join(_epb(t, pkt) for t, pkt in packets))
