"""Relays of the suite's own tests: a target behind them behaves in one way the guide or a bug allows.

``Relay`` listens on 127.0.0.1:0 for every port of the target behind it and passes bytes on, one thread per
direction, half-close included. What it changes, each optional:
- ``rewrite``: the replies, frame by frame - a function from a decoded reply to the one the client gets (the
  absurd values of issue 32: the pose as little-endian doubles, NaN and infinities); the reply is encoded again
  from the spec, so a value the wire type carries reaches the client as it is;
- ``accept_every``: the accept loop runs on a timer (a GUI application's): a newcomer waits in the listen
  backlog until the next tick, so its first reply comes up to that much later (issue 32: 100 ms).

``python -m tests.conformance_tests.relays --upstream 127.0.0.1:10000,10002 --absurd le-pose`` runs one by hand
(it prints its ports), for a ``pltf conform`` of one's own.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import socket
import struct
import threading
import time
from collections.abc import Callable
from typing import Any

from pltf.spec.codec import HEADER, REPLIES, encode
from pltf.spec.errors import RemoteProtocolError
from pltf.spec.telegram import Telegram, user_fields

Rewrite = Callable[[Telegram], Telegram]
_HEAD = struct.Struct(">4sI")


class Relay:
    def __init__(
        self, upstream: list[int], *, rewrite: Rewrite | None = None, accept_every: float = 0.0, host: str = "127.0.0.1"
    ) -> None:
        self.upstream, self.host = upstream, host
        self.rewrite, self.accept_every = rewrite, accept_every
        self._listeners = [self._listen() for _ in upstream]
        self.ports = [ls.getsockname()[1] for ls in self._listeners]
        self._stop = threading.Event()
        self.rewritten = 0  # replies rewritten (the tests check the relay did its part)

    def _listen(self) -> socket.socket:
        ls = socket.socket()
        ls.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        ls.bind((self.host, 0))
        ls.listen(16)
        return ls

    def __enter__(self) -> Relay:
        for ls, up in zip(self._listeners, self.upstream, strict=True):
            threading.Thread(target=self._accept, args=(ls, up), daemon=True).start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        for ls in self._listeners:
            with contextlib.suppress(OSError):
                ls.shutdown(socket.SHUT_RDWR)
            ls.close()

    def _accept(self, ls: socket.socket, up: int) -> None:
        ls.settimeout(None if not self.accept_every else 0.0)
        while not self._stop.is_set():
            if self.accept_every:
                time.sleep(self.accept_every)  # the timer's tick: everyone waiting is taken now
            while True:
                try:
                    client, _ = ls.accept()
                except (BlockingIOError, TimeoutError):
                    break
                except OSError:
                    return
                client.setblocking(True)
                threading.Thread(target=self._serve, args=(client, up), daemon=True).start()
                if not self.accept_every:
                    break

    def _serve(self, client: socket.socket, up: int) -> None:
        try:
            server = socket.create_connection((self.host, up), timeout=5.0)
        except OSError:
            client.close()
            return
        server.settimeout(None)
        for s in (client, server):
            s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        back = threading.Thread(target=self._replies, args=(server, client), daemon=True)
        back.start()
        _pump(client, server, lambda data: data)
        back.join()
        for s in (client, server):
            s.close()

    def _replies(self, server: socket.socket, client: socket.socket) -> None:
        if self.rewrite is None:
            _pump(server, client, lambda data: data)
            return
        buf = bytearray()

        def frames(data: bytes) -> bytes:
            buf.extend(data)
            out = bytearray()
            while len(buf) >= _HEAD.size:
                head, n = _HEAD.unpack_from(buf)
                if head != HEADER or len(buf) < _HEAD.size + n:
                    break
                raw = bytes(buf[: _HEAD.size + n])
                del buf[: _HEAD.size + n]
                out += self._rewritten(raw)
            if buf and buf[:4] != HEADER[: len(buf[:4])]:
                out += buf  # out of step: passed on as it is
                buf.clear()
            return bytes(out)

        _pump(server, client, frames)

    def _rewritten(self, raw: bytes) -> bytes:
        assert self.rewrite is not None
        try:
            reply = REPLIES.decode_data(raw[_HEAD.size :])
        except RemoteProtocolError:
            return raw
        new = self.rewrite(reply)
        if new is reply:
            return raw
        self.rewritten += 1
        return encode(new)


def _pump(src: socket.socket, dst: socket.socket, shape: Callable[[bytes], bytes]) -> None:
    """``src`` to ``dst`` until ``src``'s end-of-stream, which is passed on (half-close)."""
    with contextlib.suppress(OSError):
        while data := src.recv(65536):
            if out := shape(data):
                dst.sendall(out)
    with contextlib.suppress(OSError):
        dst.shutdown(socket.SHUT_WR)


# ---- the absurd values of issue 32


def _le(value: float) -> float:
    """A double as a client reads it when the target wrote it little-endian."""
    (out,) = struct.unpack(">d", struct.pack("<d", value))
    return float(out)


def fields_set(name: str, values: dict[str, Any]) -> Rewrite:
    """Replies to ``name`` carry ``values`` (field -> value) instead of their own; the other replies pass."""

    def rewrite(reply: Telegram) -> Telegram:
        return reply._replace(**values) if name == reply.NAME else reply  # type: ignore[attr-defined, no-any-return]

    return rewrite


def doubles_of(name: str) -> list[str]:
    return [f.name for f in user_fields(REPLIES[name].DEF.reply or ()) if f.type == "DOUBLE" and not f.repeat]


def le_pose(reply: Telegram) -> Telegram:
    """The pose's doubles of CMD_GET_POSITION written little-endian (the issue's ~1e85 rad angle)."""
    if reply.NAME != "CMD_GET_POSITION":
        return reply
    return reply._replace(**{n: _le(getattr(reply, n)) for n in doubles_of(reply.NAME)})  # type: ignore[attr-defined, no-any-return]


def every_double(value: float) -> Rewrite:
    """Every double of CMD_GET_POSITION and CMD_GET_STATUS is ``value`` (NaN, an infinity)."""
    names = {n: doubles_of(n) for n in ("CMD_GET_POSITION", "CMD_GET_STATUS")}

    def rewrite(reply: Telegram) -> Telegram:
        if reply.NAME not in names:
            return reply
        return reply._replace(**dict.fromkeys(names[reply.NAME], value))  # type: ignore[attr-defined, no-any-return]

    return rewrite


ABSURD: dict[str, Rewrite] = {
    "le-pose": le_pose,
    "nan": every_double(math.nan),
    "inf": every_double(math.inf),
    "-inf": every_double(-math.inf),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--upstream", required=True, help="HOST:PORT,PORT2 of the target behind")
    ap.add_argument("--absurd", choices=sorted(ABSURD))
    ap.add_argument("--accept-every-ms", type=float, default=0.0)
    args = ap.parse_args()
    host, ports = args.upstream.rsplit(":", 1)
    relay = Relay(
        [int(p) for p in ports.split(",")],
        rewrite=ABSURD.get(args.absurd),
        accept_every=args.accept_every_ms / 1000,
        host=host,
    )
    with relay:
        print("relay ports:", ",".join(map(str, relay.ports)), flush=True)
        with contextlib.suppress(KeyboardInterrupt):
            threading.Event().wait()


if __name__ == "__main__":
    main()
