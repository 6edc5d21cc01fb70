"""Write a finding: a standalone reproducer script, the hex, a JSON description and a pcapng.

Rules: the reproducer imports nothing but the standard library, so it runs against any implementation on
any machine: ``python repro.py --target HOST:PORT [--second-port PORT]``; it exits 1 when the failure
happened again (the target died, hung, stalled or answered garbage), 0 when the target survived.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

from pltf.fuzz.pcapng import Conversation, write_pcapng
from pltf.fuzz.target import Outcome, Session
from pltf.fuzz.wire import split_frames
from pltf.spec import errors
from pltf.spec.codec import REQUESTS

_SCRIPT = '''#!/usr/bin/env python3
"""Reproducer of a pltf fuzz finding: {kind}. {reason}

Found by: {command}
Usage: python {name} --target HOST:PORT [--second-port PORT] [--deadline SECONDS]
Exit status: 1 when the failure happened again ({kind}), 0 when the target survived, 2 on a usage error.
Standard library only; it replays {n_frames} frame(s) on {n_sessions} connection(s), then probes liveness with
CMD_GET_STATUS on --second-port (or the same port).
"""

import argparse
import socket
import sys
import time

KIND = {kind!r}
SESSIONS = {sessions}
GET_STATUS = bytes.fromhex("ff01fe020000000112")
HEADER = bytes.fromhex("ff01fe02")
try:  # strict reply checks when the pltf toolkit is importable; framing checks only otherwise
    from pltf.spec.codec import REPLIES
    from pltf.spec.errors import RemoteProtocolError
except ImportError:
    REPLIES = None


def strict(data):
    """Why a reply's data (identifier first) does not decode strictly, or None."""
    if REPLIES is None:
        return None
    try:
        REPLIES.decode_data(data)
    except RemoteProtocolError as exc:
        return "reply does not decode: %s: %s" % (type(exc).__name__, exc)
    return None


def chunks(data, delivery):
    mode, pieces, pause = delivery
    if mode == "bytewise":
        return [(data[i:i + 1], 0.0) for i in range(len(data))]
    if mode == "slow" and pieces > 1 and len(data) > 1:
        n = min(pieces, len(data))
        pause = min(pause, 0.05 / n)
        cuts = [len(data) * k // n for k in range(n + 1)]
        return [(data[a:b], pause if k else 0.0) for k, (a, b) in enumerate(zip(cuts, cuts[1:]))]
    return [(data, 0.0)]


def read_frames(sock, want, deadline):
    """Read replies until `want` frames (None: until EOF); returns (frames, problem, timed_out)."""
    buf, frames = b"", []
    while want is None or len(frames) < want:
        while len(buf) >= 8:
            if buf[:4] != HEADER:
                return frames, "reply with a bad header " + buf[:4].hex(), False
            n = int.from_bytes(buf[4:8], "big")
            if len(buf) < 8 + n:
                break
            problem = strict(buf[8:8 + n])
            if problem:
                return frames, problem, False
            frames.append(buf[8:8 + n])
            buf = buf[8 + n:]
            if want is not None and len(frames) >= want:
                return frames, None, False
        left = deadline - time.monotonic()
        if left <= 0:
            return frames, None, True
        sock.settimeout(left)
        try:
            data = sock.recv(65536)
        except socket.timeout:
            return frames, None, True
        except OSError:
            data = b""
        if not data:
            return frames, ("reply cut off by the close" if buf else None), False
        buf += data
    return frames, None, False


def play(host, port, session, deadline_s):
    """'refused', 'stall', 'dropped', 'bad-reply: ...' or None."""
    try:
        sock = socket.create_connection((host, port), timeout=deadline_s)
    except ConnectionRefusedError:
        return "refused"
    except OSError:
        return None
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    try:
        data = bytes.fromhex(session["frames"])
        try:
            for chunk, pause in chunks(data, session["delivery"]):
                if pause:
                    time.sleep(pause)
                sock.sendall(chunk)
            if session["sync"]:
                sock.sendall(GET_STATUS)
            if session["half_close"]:
                sock.shutdown(socket.SHUT_WR)
        except OSError:
            return None
        want = session["replies"] if session["sync"] and not session["half_close"] else None
        frames, problem, timed_out = read_frames(sock, want, time.monotonic() + deadline_s)
        if problem:
            return "bad-reply: " + problem
        if timed_out:
            return "stall"
        if session["sync"] and len(frames) < session["replies"]:
            return "dropped"
        return None
    finally:
        sock.close()


def probe(host, port, deadline_s):
    """None when GET_STATUS is answered, else 'dead', 'hang' or 'deaf'."""
    try:
        sock = socket.create_connection((host, port), timeout=deadline_s)
    except ConnectionRefusedError:
        return "dead"
    except OSError:
        return "hang"
    try:
        sock.sendall(GET_STATUS)
        frames, problem, timed_out = read_frames(sock, 1, time.monotonic() + deadline_s)
    except OSError:
        return "dead"
    finally:
        sock.close()
    if timed_out:
        return "hang"
    if not frames or frames[0][:1] != b"\\x12":
        return "deaf"
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--target", required=True, metavar="HOST:PORT")
    parser.add_argument("--second-port", type=int, help="port of the liveness probe (default: the same port)")
    parser.add_argument("--deadline", type=float, default={deadline!r})
    args = parser.parse_args()
    host, _, port = args.target.rpartition(":")
    if not host or not port.isdigit():
        parser.error("--target must be HOST:PORT")
    port = int(port)
    verdict = None
    for session in SESSIONS:
        verdict = play(host, port, session, args.deadline)
        if verdict == "refused":
            verdict = "dead"
            break
        if verdict:
            break
    time.sleep(0.05)
    after = probe(host, args.second_port or port, args.deadline)
    if after is not None:
        verdict = after
    if verdict is None:
        print("target survived: the failure did not happen again")
        return 0
    print("reproduced:", verdict)
    return 1


if __name__ == "__main__":
    sys.exit(main())
'''


def slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text)[:60]


def describe_frames(data: bytes) -> list[str]:
    """A readable name per frame (strict decode where possible)."""
    out = []
    for f in split_frames(data):
        try:
            t = REQUESTS.decode_data(f[8:]) if len(f) > 8 and f[:4] == b"\xff\x01\xfe\x02" else None
            out.append(repr(t) if t is not None else f"raw {f[:24].hex()}{'...' if len(f) > 24 else ''}")
        except errors.RemoteProtocolError as exc:
            name = (
                REQUESTS.by_id[f[8]].NAME
                if len(f) > 8 and f[8] in REQUESTS.by_id
                else f"id {f[8] if len(f) > 8 else '?'}"
            )
            out.append(f"{name} malformed ({type(exc).__name__}: {str(exc)[:120]}), {len(f)} bytes")
    return out


def script_sessions(sessions: list[Session]) -> list[dict[str, Any]]:
    from pltf.fuzz.target import expected_reply_ids

    return [
        {
            "frames": s.data.hex(),
            "delivery": [s.delivery.mode, s.delivery.pieces, s.delivery.pause],
            "half_close": s.half_close,
            "sync": s.sync,
            "replies": len(expected_reply_ids(s.data)) + (1 if s.sync else 0),
        }
        for s in sessions
    ]


def write_finding(
    directory: Path,
    kind: str,
    reason: str,
    sessions: list[Session],
    description: dict[str, Any],
    outcomes: list[Outcome],
    server_port: int,
    deadline: float,
) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    frames = [f for s in sessions for f in s.frames]
    (directory / "sequence.hex").write_text("".join(f"{s.data.hex()}\n" for s in sessions))
    sess = script_sessions(sessions)
    sessions_src = "[\n" + "".join(f"    {d!r},\n" for d in sess) + "]"
    script = _SCRIPT.format(
        kind=kind,
        reason=reason.replace('"""', "'''").replace("\\", "/")[:300],
        command=description.get("command", "pltf fuzz"),
        name="repro.py",
        n_frames=len(frames),
        n_sessions=len(sessions),
        sessions=sessions_src,
        deadline=deadline,
    )
    (directory / "repro.py").write_text(script)
    desc = dict(description)
    desc.update(
        kind=kind,
        reason=reason,
        frames=len(frames),
        telegrams=[d for s in sessions for d in describe_frames(s.data)][:200],
        sessions=[s.to_json() for s in sessions]
        if sum(len(s.data) for s in sessions) < 1 << 20
        else "see sequence.hex",
        replay="python repro.py --target HOST:PORT [--second-port PORT]",
    )
    (directory / "finding.json").write_text(json.dumps(desc, indent=2, default=str) + "\n")
    convs = []
    for k, out in enumerate(outcomes):
        events = [(t, "c2s", b) for t, b in out.sent] + [(t, "s2c", b) for t, b in out.received]
        events.sort(key=lambda e: e[0])
        convs.append(Conversation(40_000 + k, server_port, events, client_fin=True, server_fin=out.closed))
    write_pcapng(directory / "exchange.pcapng", convs)
    return directory
