"""A small PlatformCtrl server with one deliberate bug, for the fuzzer's tests.

``python tests/fuzz/fragile_server.py --ports 0,0 --bug NAME`` listens on 127.0.0.1 (the reference server's
conventions: ``server started at port N`` per port, one client per port, GET_* answered, malformed input
closes that connection). Without a bug it is a well-behaved target. Bugs (each imitates a classic C++ slip):

- ``negative-repeat``: a GROUP count read as a signed size and used to allocate -> abort (process dies)
- ``doctype``: an XML document with a DOCTYPE handed to a parser that dies on it (process dies)
- ``huge-length``: a frame length over 2^31 taken as a negative size -> abort (process dies)
- ``hang-id``: telegram id 66 makes the handler busy-wait (the whole process stops answering)
- ``stall-id``: telegram id 77 makes this connection wait forever (the other port still answers)
- ``bad-reply``: CMD_GET_CAMERA is answered with a reply whose string length lies

A second client on a busy port is turned away (closed unread) as soon as asyncio hands it over - even when the
first has already sent its end-of-stream - except the first ``--admit-first N`` clients of a port, which wait
for their turn: a target that takes clients back to back at first and turns them away later.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import struct
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))

from pltf.spec import errors
from pltf.spec.codec import HEADER, REPLIES, REQUESTS, TelegramDecoder, encode
from pltf.spec.compiler import allowed_values, value_range
from pltf.spec.model import FieldDef

HANG_ID, STALL_ID = 66, 77
HANG_SECONDS = 60.0  # bounded: the tests kill the process long before


def _default(f: FieldDef) -> object:
    if f.is_group:
        return ()
    if f.type in ("STRING", "XML"):
        return ""
    allowed, rng = allowed_values(f), value_range(f)
    v: object = 0.0 if f.type == "DOUBLE" else (min(allowed) if allowed else max(0, rng[0]) if rng else 0)
    return (v,) * f.repeat if f.repeat else v


def default_reply(name: str) -> bytes:
    cls = REPLIES[name]
    layout = cls.DEF.reply or ()
    return encode(cls(*[_default(f) for f in layout if f.const is None]))


def crash(why: str) -> None:
    print(f"fragile server: crashing on {why}", flush=True)
    os._exit(134)


def check_bug(bug: str, frame: bytes) -> None:
    """The bug looks at each raw frame before the strict decoder does."""
    data = frame[8:]
    if bug == "huge-length" and struct.unpack(">I", frame[4:8])[0] >= 2**31:
        crash("a frame length over 2^31")
    if not data:
        return
    is_path = data[0] == REQUESTS.CMD_MOVE_PATH.ID and len(data) >= 5
    if bug == "negative-repeat" and is_path and struct.unpack(">i", data[1:5])[0] < 0:
        crash("a negative repeat count")
    if bug == "doctype" and data[0] in (25, 32, 40) and b"<!DOCTYPE" in data:
        crash("a DOCTYPE")
    if bug == "hang-id" and data[0] == HANG_ID:
        deadline = time.monotonic() + HANG_SECONDS
        while time.monotonic() < deadline:  # the event loop is stuck: nothing else is served
            pass


class Port:
    def __init__(self, bug: str, admit_first: int = 0) -> None:
        self.bug = bug
        self.busy = False
        self.admit_first = admit_first
        self.clients = 0
        self.free = asyncio.Event()

    async def handle(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.clients += 1
        while self.busy and self.clients <= self.admit_first:  # the first ones wait for their turn instead
            self.free.clear()
            await self.free.wait()
        if self.busy:  # one client per port (erratum E-WIRE-007): the second one is closed at once, unread
            writer.close()
            return
        self.busy = True
        try:
            await self.serve(reader, writer)
        finally:
            self.busy = False
            self.free.set()
            writer.close()

    async def serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        dec = TelegramDecoder("request")
        buf = b""
        while True:
            data = await reader.read(65536)
            if not data:
                return
            buf += data
            while len(buf) >= 8 and buf[:4] == HEADER:  # the buggy pre-parser sees whole frames only
                n = struct.unpack(">I", buf[4:8])[0]
                if n >= 2**31:
                    check_bug(self.bug, buf[:8])
                if len(buf) < 8 + n:
                    break
                frame, buf = buf[: 8 + n], buf[8 + n :]
                check_bug(self.bug, frame)
                if self.bug == "stall-id" and len(frame) > 8 and frame[8] == STALL_ID:
                    await asyncio.sleep(HANG_SECONDS)
            dec.receive_data(data)
            try:
                for t in dec:
                    if t.NAME == "CMD_CLOSE_SOCKET":
                        return
                    if t.DEF.answered:
                        writer.write(self.reply(t.NAME))
            except errors.RemoteProtocolError:
                return
            await writer.drain()

    def reply(self, name: str) -> bytes:
        if self.bug == "bad-reply" and name == "CMD_GET_CAMERA":
            return HEADER + struct.pack(">I", 9) + bytes([59]) + struct.pack(">i", 100) + b"1234"
        return default_reply(name)


async def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--ports", default="0,0")
    parser.add_argument("--bug", default="none")
    parser.add_argument(
        "--admit-first",
        type=int,
        default=0,
        metavar="N",
        help="the first N clients of a port wait for a busy port instead of being turned away",
    )
    args = parser.parse_args()
    servers = []
    for p in args.ports.split(","):
        port = Port(args.bug, args.admit_first)
        server = await asyncio.start_server(port.handle, "127.0.0.1", int(p))
        servers.append(server)
        print(f"server started at port {server.sockets[0].getsockname()[1]}", flush=True)
    await asyncio.gather(*(s.serve_forever() for s in servers))


if __name__ == "__main__":
    asyncio.run(main())
