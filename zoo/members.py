"""The zoo's members: how each one admits clients, delays and cuts replies, and which bug it carries (a table).

Rules:
- ``admit`` says what a newcomer on a port meets: ``transparent`` - every client gets its own connection to the
  target behind, which decides (the reference server turns a second client away, the emulator leaves it in its
  backlog); ``turn-away`` - one client per port, a newcomer is accepted and closed (FIN, or RST with
  ``turn_away="rst"``; with ``"refuse"`` the port stops listening and its connect is refused) while the port
  is busy and for ``release`` seconds after its client left;
  ``backlog`` - one client per port, the next one is accepted only when the current one has left.
- ``accept_every`` > 0: the accept loop runs on a timer (every so many seconds, as a GUI application's timer would
  run it) and takes every newcomer waiting in the backlog then; a newcomer is served up to that long after its
  connect succeeded (the kernel completes the handshake at once).
- How a member ends a connection (matrix rows 1, 3, 7, 8; spec/errata/behaviour.yaml): ``on_fin`` "pass" lets
  a client's half-close travel (the target may still answer), "end" ends the whole session at the client's FIN
  (replies still owed are lost); ``close`` "rst" resets the client's connection wherever it would close it;
  ``idle_drop`` closes a client that sent nothing for so many seconds; ``malformed`` "close" closes on a malformed
  frame or an unknown command (after the replies owed for the frames before it), "skip" drops such a frame and
  goes on ("": the target behind decides; both the reference server and the emulator close, E-WIRE-006).
- ``silent`` (row 9): on a connection, every request before its CMD_CONNECT_TO_PLTF is swallowed unanswered (a
  gateway that wants a greeting first; spec/errata/behaviour.yaml E-BEH-009 has the platform-wide reading too).
- ``backlog`` is the listen backlog (row 6: 1); ``host`` the address it listens on by default (row 12: ::1);
  ``restart_every`` (row 10): every so many seconds the member drops every connection, stops listening for
  ``restart_down`` seconds and starts the target behind it afresh (state lost).
- ``absurd`` names a style of values.py: the doubles of the position and status replies are rewritten.
- ``conforming`` members pass the standard conformance tier under ``profile`` (a test holds them to it);
  the others carry a planted bug and fail it.
- Everything a member does is decided here and in bugs.py/schedule.py; relay.py only moves the bytes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from pltf.spec.codec import REQUESTS
from pltf.zoo.bugs import Bug, CrashAfterStart, HangOnUnknownKey, Leak
from pltf.zoo.schedule import Delay, for_ident, jitter, no_delay

GET_STATUS_ID = REQUESTS.CMD_GET_STATUS.ID


@dataclass(frozen=True)
class Member:
    name: str
    summary: str
    conforming: bool
    profile: str = "strict"  # the profile the standard tier passes it under (conforming members)
    admit: str = "transparent"  # "transparent", "turn-away" or "backlog"
    turn_away: str = "fin"  # "fin", "rst" or "refuse"
    release: tuple[float, float] = (0.0, 0.0)  # s after a client left until its port takes the next one
    delay: Delay = no_delay
    segment: int = 0  # replies cut into writes of 1..segment bytes (0: as they come)
    bug: Callable[[], Bug] | None = None
    accept_every: float = 0.0  # s between two runs of a timer-driven accept loop (0: accept at once)
    absurd: str = ""  # a style of values.py: the doubles of GET_POSITION and GET_STATUS rewritten
    on_fin: str = "pass"  # "pass" (half-close travels) or "end" (the client's FIN ends the session)
    close: str = "fin"  # "fin" or "rst": how the member closes a client's connection
    idle_drop: float = 0.0  # s of silence from a client after which the member closes it (0: never)
    malformed: str = ""  # a malformed frame or an unknown command: "close", "skip" ("": as the target behind does)
    silent: bool = False  # nothing answered before CMD_CONNECT_TO_PLTF
    backlog: int = 16  # the listen backlog
    host: str = "127.0.0.1"  # the address it listens on unless --host says otherwise
    restart_every: float = 0.0  # s between two restarts (0: never)
    restart_down: float = 2.0  # s the ports are gone at a restart

    @property
    def shapes_replies(self) -> bool:
        return self.delay is not no_delay or self.segment > 0 or bool(self.absurd)

    @property
    def cuts_requests(self) -> bool:
        """Whether the requests are cut into frames on their way (a bug, a strict or a silent member)."""
        return self.bug is not None or bool(self.malformed) or self.silent


MEMBERS: dict[str, Member] = {
    m.name: m
    for m in (
        Member("faithful", "a plain relay: every byte passed on as it comes (the control)", True),
        Member(
            "slow-release",
            "one client per port; the port is free 5-50 ms after its client left, newcomers are "
            "turned away (accepted and closed, FIN) until then",
            True,
            admit="turn-away",
            release=(0.005, 0.05),
        ),
        Member(
            "slow-release-rst",
            "as slow-release, but a newcomer is turned away with a reset (RST)",
            True,
            admit="turn-away",
            turn_away="rst",
            release=(0.005, 0.05),
        ),
        Member(
            "slow-link",
            "replies 50-200 ms late with jitter, several replies that fall due together coalesced "
            "into one write, every write cut into segments of 1-7 bytes",
            True,
            delay=jitter(0.05, 0.2),
            segment=7,
        ),
        Member(
            "accept-once",
            "one client per port; a newcomer waits in the listen backlog until the client before it "
            "has left (erratum E-WIRE-007, first alternative reading)",
            True,
            profile="original",
            admit="backlog",
        ),
        Member(
            "fin-ends-session",
            "the client's FIN (half-close) ends the whole session: the connection behind is closed at once and the "
            "replies still owed are lost (matrix row 1)",
            True,
            on_fin="end",
        ),
        Member(
            "close-rst",
            "closes a client's connection with a reset (RST) instead of a FIN: after CMD_CLOSE_SOCKET, when the "
            "target closes, after the client's FIN (matrix row 3)",
            True,
            close="rst",
        ),
        Member(
            "backlog-one",
            "one client per port with a listen backlog of 1: a newcomer waits in the backlog, the SYNs beyond it "
            "are dropped (the connect times out or retries; matrix row 6)",
            True,
            profile="original",
            admit="backlog",
            backlog=1,
        ),
        Member(
            "idle-drop",
            "closes a client that sent nothing for 10 s (--idle-seconds; matrix row 7)",
            True,
            idle_drop=10.0,
        ),
        Member(
            "strict-framing",
            "closes the connection on a malformed frame or an unknown command instead of skipping it, after the "
            "replies owed for the frames before it (matrix row 8; E-WIRE-006's decision, whatever the target does)",
            True,
            malformed="close",
        ),
        Member(
            "lenient-framing",
            "skips a malformed frame or an unknown command and goes on: the frame is dropped unanswered (matrix row "
            "8, E-WIRE-006's alternative reading 'ignore the telegram and go on')",
            True,
            profile="original",
            malformed="skip",
        ),
        Member(
            "silent-until-connect",
            "answers nothing before CMD_CONNECT_TO_PLTF: on a connection, every request before it is swallowed "
            "(matrix row 9)",
            True,
            silent=True,
        ),
        Member(
            "restarts",
            "restarts every 60 s (--restart-every): every connection dropped, the ports gone for 2 s, then a fresh "
            "target behind (state lost; matrix row 10)",
            True,
            restart_every=60.0,
        ),
        Member(
            "ipv6-only",
            "listens on [::1] only: an IPv4 connect to 127.0.0.1 is refused (matrix row 12)",
            True,
            host="::1",
        ),
        Member(
            "slow-accept",
            "the accept loop runs every 100 ms (a GUI application's timer): a newcomer is served up to 100 ms "
            "after its connect succeeded (matrix row 5)",
            True,
            accept_every=0.1,
        ),
        Member(
            "absurd-values",
            "reports absurd values: the doubles of GET_POSITION and GET_STATUS (the pose, the velocities, the GPS "
            "position) as little-endian doubles (--absurd nan|inf: NaN or infinity in each)",
            False,
            absurd="little-endian",
        ),
        Member(
            "crash-after-start",
            "planted bug: in Running, a path command (MOVE_ABS/REL/PATH/TO_STATION) while the "
            "motion mode is not Automatic kills the target (needs CONNECT, INIT, START first)",
            False,
            bug=CrashAfterStart,
        ),
        Member(
            "hang-unknown-key",
            "planted bug: CMD_SET_PLTF_PARAM with an unknown key hangs the whole target: no "
            "port answers any more, newcomers wait in the backlog",
            False,
            bug=HangOnUnknownKey,
        ),
        Member(
            "leak",
            "planted bug: every request leaks 32 KiB; at 64 MiB (2,048 requests) the target runs out of "
            "memory and dies",
            False,
            bug=Leak,
        ),
        Member(
            "slow-status",
            "planted bug: every CMD_GET_STATUS reply comes 12 s late (the replies behind it wait)",
            False,
            delay=for_ident(GET_STATUS_ID, 12.0),
        ),
    )
}


def member(name: str) -> Member:
    try:
        return MEMBERS[name]
    except KeyError:
        raise KeyError(f"no zoo member {name!r} (members: {', '.join(MEMBERS)})") from None
