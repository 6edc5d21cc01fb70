"""What the target was sent, in the order it was sent: the recent sessions of both lanes cut where a write of
another connection came between, for a replay that rebuilds a state the two lanes reached together. No sockets.

Rules:
- A target's state may be process-wide (a platform has one operation state, whichever port a command came in
  on; guide 6.1 "For each port one client is able to connect", both ports take every command), and two lanes
  (``pltf.fuzz.lanes``) keep units of both ports in flight at once, pipelined ones connected and sent while they
  wait: a death may need the frames of several connections in the order they arrived. Neither the order the
  units were judged in nor the order they were started in is that order (a gated unit sends its cases only after
  its lead was answered, a big one in several writes).
- Every write of every flight has a place in one order (``pltf.fuzz.flight.Flight.sends``). A frame was sent
  with the write that carried its last byte; a frame never sent whole is left out (the target never read it).
- A *segment* is a run of consecutive frames of one flight sent with no write of another flight between them.
  Each replays as a session of its own, one after the other (the next connection only once the target closed
  the one before): led, our write side shut at its end, written whole. The flight's own lead is left out (the
  segment's lead replaces it); a segment of nothing but the lead is left out.
- This is the order we wrote in; a target reading several connections may see them in another. For a state fed
  by every connection it is the closest sequential replay there is; the other candidates of a finding
  (``pltf.fuzz.findings``) come first.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable

from pltf.fuzz.target import GET_STATUS, LEAD, Session

Sent = tuple[Session, bytes, list[tuple[int, int]]]  # a flight's session, the bytes it wrote, (order, end) per write


def frames_of(session: Session, data: bytes) -> list[bytes]:
    """The frames a flight wrote: the session's, and the sync GET_STATUS its flight appends."""
    return [*session.frames, GET_STATUS] if len(data) > len(session.data) else list(session.frames)


def segments(flights: Iterable[Sent]) -> list[Session]:
    """The frames of ``flights`` in the order their writes went out, as sessions to replay one after the other."""
    events: list[tuple[int, int, int, int]] = []  # (order of the write, flight, first frame, end frame)
    frames: list[list[bytes]] = []
    for n, (session, data, sends) in enumerate(flights):
        mine = frames_of(session, data)
        frames.append(mine)
        ends = list(itertools.accumulate(map(len, mine)))
        i = int(session.led)  # the flight's lead: the segment's own lead replaces it
        for order, end in sends:
            j = i
            while j < len(mine) and ends[j] <= end:
                j += 1
            if j > i:
                events.append((order, n, i, j))
                i = j
    events.sort()
    merged: list[tuple[int, int, int]] = []
    for _, n, i, j in events:
        if merged and merged[-1][0] == n and merged[-1][2] == i:
            merged[-1] = (n, merged[-1][1], j)
        else:
            merged.append((n, i, j))
    return [Session([LEAD, *frames[n][i:j]], half_close=True, led=True) for n, i, j in merged]


__all__ = ["Sent", "frames_of", "segments"]
