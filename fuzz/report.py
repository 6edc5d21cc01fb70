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

from pltf.fuzz.target import LEAD, Outcome, Session
from pltf.fuzz.wire import split_frames
from pltf.harness.pcapng import Conversation, write_pcapng
from pltf.spec import errors
from pltf.spec.codec import REQUESTS

_SCRIPT = '''#!/usr/bin/env python3
"""Reproducer of a pltf fuzz finding: {kind}. {reason}

Found by: {command}
Usage: python {name} --target HOST:PORT [--second-port PORT] [--deadline SECONDS]
Exit status: 1 when the failure happened again ({kind}), 0 when the target survived, 2 on a usage error.
Standard library only; it replays {n_frames} frame(s) on {n_sessions} connection(s) ({repeat} round(s)), then
probes liveness with CMD_GET_POSITION on --second-port (or the same port). Each connection opens with a
request the target answers (its lead): one that gets nothing back was not served (a target turns newcomers
away, or leaves them in its listen backlog, while a port is busy) and runs again after a short pause.
"""

import argparse
import socket
import sys
import time

KIND = {kind!r}
SESSIONS = {sessions}
REPEAT = {repeat}  # rounds of the sessions (a failure that piles up, such as a leak, needs several)
GET_STATUS = bytes.fromhex("ff01fe020000000112")
# CMD_GET_POSITION, the cheapest request a server answers (behind CMD_CONNECT_TO_PLTF where the target answers
# nothing before it): the lead the campaign's target needed
LEAD = bytes.fromhex({lead!r})
PROBE = {{"frames": LEAD.hex(), "delivery": ["whole", 1, 0.0], "half_close": True, "sync": False, "led": True,
         "gate": 0, "replies": 1, "fin_waits": True}}
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
    """Read replies until `want` frames (None: until EOF); (frames, problem, timed_out, bytes received)."""
    buf, frames, got = b"", [], 0
    while want is None or len(frames) < want:
        while len(buf) >= 8:
            if buf[:4] != HEADER:
                return frames, "reply with a bad header " + buf[:4].hex(), False, got
            n = int.from_bytes(buf[4:8], "big")
            if len(buf) < 8 + n:
                break
            problem = strict(buf[8:8 + n])
            if problem:
                return frames, problem, False, got
            frames.append(buf[8:8 + n])
            buf = buf[8 + n:]
            if want is not None and len(frames) >= want:
                return frames, None, False, got
        left = deadline - time.monotonic()
        if left <= 0:
            return frames, None, True, got
        sock.settimeout(left)
        try:
            data = sock.recv(65536)
        except socket.timeout:
            return frames, None, True, got
        except OSError:
            data = b""
        if not data:
            return frames, ("reply cut off by the close" if buf else None), False, got
        got += len(data)
        buf += data
    return frames, None, False, got


def play(host, port, session, deadline_s):
    """'refused', 'unserved' (closed with nothing back: turned away), 'unanswered' (nothing back in time: a backlog,
    or a target that stopped), 'stall', 'dropped', 'bad-reply: ...' or None."""
    try:
        sock = socket.create_connection((host, port), timeout=deadline_s)
    except ConnectionRefusedError:
        return "refused"
    except OSError:
        return "unserved"
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    deadline = time.monotonic() + deadline_s
    try:
        data = bytes.fromhex(session["frames"])
        gate, got, early = session["gate"], 0, []
        try:
            if gate:  # the lead alone; the rest once it is answered
                sock.sendall(data[:gate])
                frames, problem, timed_out, got = read_frames(sock, 1, deadline)
                if not frames:
                    return "bad-reply: " + problem if problem and got else "unanswered" if timed_out else "unserved"
                data = data[gate:]
            for chunk, pause in chunks(data, session["delivery"]):
                if pause:
                    time.sleep(pause)
                sock.sendall(chunk)
            if session["sync"]:
                sock.sendall(GET_STATUS)
            if session["half_close"] and session.get("fin_waits"):  # our FIN ends the session: the replies first
                early, problem, _, extra = read_frames(sock, session["replies"] - (1 if gate else 0), deadline)
                got += extra
                if problem:
                    return "bad-reply: " + problem
            if session["half_close"]:
                sock.shutdown(socket.SHUT_WR)
        except OSError:
            pass  # the peer is gone: what did it say before it went?
        want = session["replies"] - (1 if gate else 0) if session["sync"] and not session["half_close"] else None
        frames, problem, timed_out, more = read_frames(sock, want, deadline)
        frames = early + frames
        if session["led"] and not got and not more:
            return "unanswered" if timed_out else "unserved"
        if problem and not (problem.startswith("reply cut") and not session["sync"]):
            return "bad-reply: " + problem
        if timed_out:
            return "stall"
        if session["sync"] and len(frames) + (1 if gate else 0) < session["replies"]:
            return "dropped"
        return None
    finally:
        sock.close()


def play_served(host, port, session, deadline_s, patience):
    """`play` again, after a growing pause, while the target does not serve us (up to `patience` s)."""
    end, pause = time.monotonic() + patience, 0.001
    while True:
        verdict = play(host, port, session, deadline_s)
        if verdict not in ("refused", "unserved", "unanswered") or time.monotonic() >= end:
            return verdict
        time.sleep(pause)
        pause = min(0.016, pause * 1.6)


def probe(host, port, deadline_s, patience):
    """None when the lead (CMD_GET_POSITION) is answered (waiting for the port as `play_served` does), else
    'dead', 'hang' or 'deaf'."""
    verdict = play_served(host, port, PROBE, deadline_s, patience)
    if verdict is None:
        return None
    return {{"refused": "dead", "stall": "hang", "unanswered": "hang", "unserved": "deaf"}}.get(verdict, "deaf")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--target", required=True, metavar="HOST:PORT")
    parser.add_argument("--second-port", type=int, help="port of the liveness probe (default: the same port)")
    parser.add_argument("--deadline", type=float, default={deadline!r})
    parser.add_argument("--patience", type=float, help="s to wait for a port that turns us away (default: "
                        "twice the deadline, at least 1)")
    args = parser.parse_args()
    host, _, port = args.target.rpartition(":")
    if not host or not port.isdigit():
        parser.error("--target must be HOST:PORT")
    port = int(port)
    second = args.second_port or port
    patience = args.patience or max(1.0, 2 * args.deadline)
    verdict = None
    for _ in range(REPEAT):
        for session in SESSIONS:
            verdict = play_served(host, port, session, args.deadline, patience)
            if verdict:
                break
        if verdict or (REPEAT > 1 and probe(host, second, args.deadline, patience)):
            break
    time.sleep(0.05)
    after = probe(host, second, args.deadline, patience)
    if after is not None:
        verdict = after
    elif verdict in ("refused", "unserved", "unanswered"):
        verdict = "stall"  # this port no longer serves us while the other one does
    if verdict is None:
        print("target survived: the failure did not happen again")
        return 0
    print("reproduced:", verdict.replace("refused", "dead"))
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
            "led": s.led,
            "gate": s.gate_bytes,
            "replies": len(expected_reply_ids(s.data)) + (1 if s.sync else 0),
            "fin_waits": s.fin_waits,
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
    repeat: int = 1,
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
        repeat=repeat,
        lead=next((s.frames[0] for s in sessions if s.led), LEAD).hex(),
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
        repeat=repeat,
    )
    (directory / "finding.json").write_text(json.dumps(desc, indent=2, default=str) + "\n")
    convs = []
    for k, out in enumerate(outcomes):
        events = [(t, "c2s", b) for t, b in out.sent] + [(t, "s2c", b) for t, b in out.received]
        events.sort(key=lambda e: e[0])
        convs.append(Conversation(40_000 + k, server_port, events, client_fin=True, server_fin=out.closed))
    write_pcapng(directory / "exchange.pcapng", convs)
    return directory
