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

    @property
    def shapes_replies(self) -> bool:
        return self.delay is not no_delay or self.segment > 0 or bool(self.absurd)


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
