"""The proxy's pcapng recording: each proxied connection as one TCP conversation between the client and the
target, written packet by packet as the bytes pass (harness/pcapng.py builds the packets).

Rules: a segment is what one read returned, so the file shows how the bytes were really cut (telegrams split
across segments, several in one); each conversation gets its handshake when it opens and a FIN per direction
when that side closes. Addresses are the client's and the target's (IPv4; anything else is written as
127.0.0.1). Opening in Wireshark: ``wireshark -X lua_script:proxy/pltf.lua FILE`` (ports other than 10000
and 10002: Decode As... PLTF).
"""

from __future__ import annotations

import ipaddress
import itertools
from pathlib import Path
from typing import IO

from pltf.harness.pcapng import CLIENT_IP, TcpFlow, enhanced_packet, file_header


def ipv4(host: str, default: bytes = CLIENT_IP) -> bytes:
    try:
        addr = ipaddress.ip_address(host)
    except ValueError:
        return default
    return addr.packed if addr.version == 4 else default


class PcapngWriter:
    def __init__(self, path: Path) -> None:
        self.path = path
        self._fh: IO[bytes] = path.open("wb")
        self._fh.write(file_header())
        self._ident = itertools.count(1)
        self._flows: dict[int, TcpFlow] = {}
        self.packets = 0

    def _write(self, packets: list[tuple[float, bytes]]) -> None:
        self._fh.write(b"".join(enhanced_packet(t, pkt) for t, pkt in packets))
        self.packets += len(packets)

    def opened(self, conn: int, now: float, client: tuple[str, int], target: tuple[str, int]) -> None:
        flow = TcpFlow(client[1], target[1], self._ident, client_ip=ipv4(client[0]), server_ip=ipv4(target[0]))
        self._flows[conn] = flow
        self._write(flow.handshake(now))

    def data(self, conn: int, now: float, c2s: bool, payload: bytes) -> None:
        flow = self._flows.get(conn)
        if flow is not None and payload:
            self._write(flow.data(now, c2s, payload))

    def fin(self, conn: int, now: float, c2s: bool) -> None:
        flow = self._flows.get(conn)
        if flow is not None:
            self._write(flow.fin(now, c2s))

    def forget(self, conn: int) -> None:
        self._flows.pop(conn, None)

    def flush(self) -> None:
        self._fh.flush()

    def close(self) -> None:
        self._fh.close()
