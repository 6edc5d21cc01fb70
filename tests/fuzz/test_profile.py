"""fuzz/profile: what the opening phase learns, and the sessions it adapts, against a real loopback server whose
FIN ends the session (matrix row 1) - the replies owed at our FIN are lost unless the FIN waits for them."""

from __future__ import annotations

import select
import socket
import struct
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from pltf.fuzz.engine import Campaign, HarnessError, Options, exchange
from pltf.fuzz.flight import Flight, fly
from pltf.fuzz.lanes import InFlight
from pltf.fuzz.profile import CONNECT_TO_PLTF, SHUTDOWN_PLTF, Profile, learn
from pltf.fuzz.target import LEAD, Session, play
from pltf.fuzz.unit import Unit
from pltf.spec.codec import REPLIES, REQUESTS, TelegramDecoder, encode

POSITION_REPLY = encode(REPLIES.CMD_GET_POSITION(x=1, y=2, angle=0.0, vel_trans=0.0, vel_rot=0.0))
SET_MODE_6 = encode(REQUESTS.CMD_SET_MODE(mode=6))
GET_STATUS = encode(REQUESTS.CMD_GET_STATUS())
LATE = 0.05  # s each reply takes: our FIN, sent with the requests, always comes first


class FinEndsSession:
    """A loopback server that answers every GET_POSITION LATE s after it read it, and ends the session (closes,
    unanswered replies lost) when the client half-closes: one thread per connection."""

    def __init__(self, closed_for: float = 0.0, late: float = LATE) -> None:
        self.open_at = time.monotonic() + closed_for  # before it every client is closed at once, unanswered
        self.late = late
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.sock.settimeout(0.2)
        self.running = True
        self.thread = threading.Thread(target=self._accept, daemon=True)
        self.thread.start()

    def _accept(self) -> None:
        while self.running:
            try:
                conn, _ = self.sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            if time.monotonic() < self.open_at:
                conn.close()
                continue
            threading.Thread(target=self._serve, args=(conn,), daemon=True).start()

    def _serve(self, conn: socket.socket) -> None:
        dec = TelegramDecoder("request")
        owed: list[float] = []
        conn.settimeout(0.005)
        with conn:
            while True:
                try:
                    data = conn.recv(65536)
                except TimeoutError:
                    data = None
                except OSError:
                    return
                if data == b"" or (data and _fin_came(conn)):
                    return  # the FIN ends the session: what is still owed is lost
                if data:
                    dec.receive_data(data)
                    owed += [time.monotonic() + self.late for t in dec if t.NAME == "CMD_GET_POSITION"]
                while owed and owed[0] <= time.monotonic():
                    owed.pop(0)
                    conn.sendall(POSITION_REPLY)

    def close(self) -> None:
        self.running = False
        self.thread.join(2.0)
        self.sock.close()


def _fin_came(conn: socket.socket) -> bool:
    """Whether the client's FIN is there already, behind what was just read (as a relay sees it before it passes
    the requests on: a reply needs another process)."""
    if not select.select([conn], [], [], 0)[0]:
        return False
    try:
        return conn.recv(1, socket.MSG_PEEK) == b""
    except OSError:
        return True


@pytest.fixture
def server() -> Iterator[FinEndsSession]:
    s = FinEndsSession()
    yield s
    s.close()


def session(fin_waits: bool) -> Session:
    return Session([LEAD, LEAD, LEAD], half_close=True, led=True, fin_waits=fin_waits)


def test_a_flight_whose_fin_waits_gets_every_reply_the_fin_would_lose(server: FinEndsSession) -> None:
    hasty, patient = Flight("127.0.0.1", server.port, session(False), 2.0), None
    fly([hasty])
    patient = Flight("127.0.0.1", server.port, session(True), 2.0)
    fly([patient])
    assert len(hasty.out.replies) == 0 and hasty.out.closed  # request and FIN in one write: all lost
    assert [r.NAME for r in patient.out.replies] == ["CMD_GET_POSITION"] * 3 and patient.out.closed


def test_a_suspicions_evidence_says_when_our_fin_went_and_how_the_connection_ended(server: FinEndsSession) -> None:
    """finding.json's ``exchange``: what the campaign's connection carried, which the replays cannot show."""
    flights = {waits: Flight("127.0.0.1", server.port, session(waits), 2.0) for waits in (False, True)}
    fly(list(flights.values()))
    hasty, patient = (exchange(InFlight(f, Unit([]), 0, False, False, True, f.started)) for f in flights.values())
    assert hasty["replies"] == [] and hasty["asked"] == 3 and hasty["ended_by"] == "closed"
    assert hasty["bytes_sent"] == 3 * len(LEAD) and hasty["bytes_received"] == 0 and not hasty["fin_waits"]
    assert patient["replies"] == ["CMD_GET_POSITION"] * 3 and patient["fin_waits"]
    assert patient["our_fin_ms"] >= LATE * 1000 and patient["ended_ms"] >= patient["our_fin_ms"]  # after the replies


def test_play_and_replays_wait_too(server: FinEndsSession) -> None:
    assert len(play("127.0.0.1", server.port, session(False), 2.0).replies) == 0
    assert len(play("127.0.0.1", server.port, session(True), 2.0).replies) == 3


def test_the_opening_phase_says_the_fin_ends_the_session(server: FinEndsSession) -> None:
    prof = learn("127.0.0.1", server.port, "--target", 2.0)
    assert prof.fin_ends and not prof.silent_before_connect
    assert prof.newcomer == "served"  # this server takes every client
    assert prof.describe().startswith("ends the session at our FIN; serves a second client on a port")
    assert prof.adapt(session(False)).fin_waits


def test_a_target_that_answers_at_once_and_ends_the_session_at_our_fin_is_learnt_as_such() -> None:
    """The requests and our FIN leave in one segment: written apart, this server's thread read the requests and
    answered them all before the FIN came (a loaded machine does the same to a relay), and the opening phase took
    the target for one that answers after our FIN."""
    s = FinEndsSession(late=0.0)
    try:
        assert all(learn("127.0.0.1", s.port, "--target", 2.0).fin_ends for _ in range(5))
    finally:
        s.close()


class EndsWithReset(FinEndsSession):
    """Answers every GET_POSITION at once, and at the client's FIN ends the session with a reset (SO_LINGER 0),
    as zoo member close-rst does (matrix row 3): what it sent that the client had not read yet is lost."""

    def _serve(self, conn: socket.socket) -> None:
        dec = TelegramDecoder("request")
        with conn:
            while data := conn.recv(65536):
                dec.receive_data(data)
                conn.sendall(b"".join(POSITION_REPLY for t in dec if t.NAME == "CMD_GET_POSITION"))
            conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))


def test_a_target_that_ends_its_sessions_with_a_reset_gets_a_fin_that_waits_for_the_replies() -> None:
    """A reset throws away what the target sent and we had not read yet (slow-tier: a 67 KB GET_STATUS reply cut
    behind close-rst on a loaded machine, confirmed by two of three replays): the campaign relies on no orderly
    close, as where our FIN ends the session."""
    s = EndsWithReset()
    try:
        prof = learn("127.0.0.1", s.port, "--target", 2.0)
    finally:
        s.close()
    assert prof.resets and not prof.fin_ends
    assert "answers after our FIN; ends a session with RST: our FIN waits for the replies owed" in prof.describe()
    assert prof.adapt(session(False)).fin_waits
    assert not Profile().fin_waits and Profile(fin_ends=True).fin_waits


def test_a_port_that_turns_us_away_for_a_second_is_learnt_within_the_deadline() -> None:
    """A loaded target (or the relay in front of it) may turn fresh connections away for longer than the twenty
    quick tries of the opening phase took (0.1-0.4 s): it keeps trying for the deadline."""
    s = FinEndsSession(closed_for=1.0)
    try:
        assert learn("127.0.0.1", s.port, "--target", 3.0).fin_ends
    finally:
        s.close()


def test_nothing_learnt_from_a_port_nobody_listens_on_names_port_and_flag() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(RuntimeError, match=rf"nothing listening on 127.0.0.1:{port} \(--second-port\)"):
        learn("127.0.0.1", port, "--second-port", 1.0)


def test_a_silent_target_gets_connect_to_pltf_in_its_lead_and_after_every_shutdown() -> None:
    prof = Profile(silent_before_connect=True)
    s = prof.adapt(Session([LEAD, SHUTDOWN_PLTF, LEAD], half_close=True, led=True))
    assert s.frames == [CONNECT_TO_PLTF + LEAD, SHUTDOWN_PLTF + CONNECT_TO_PLTF, LEAD]
    assert not s.fin_waits  # its FIN does not end the session
    unled = prof.adapt(Session([SET_MODE_6, GET_STATUS], half_close=True))  # a session past the first units
    assert unled.frames == [CONNECT_TO_PLTF + SET_MODE_6, GET_STATUS]  # its prelude's reply is owed: connect first
    plain = Session([LEAD], half_close=True, led=True)
    assert Profile().adapt(plain) is plain  # a target with no such manners: the session as it was


def test_a_slow_set_up_makes_fresh_connections_dear_only_when_it_dwarfs_a_reply() -> None:
    assert Profile(setup_ms=50.0, reply_ms=0.3).slow_setup  # a 100 ms accept timer
    assert not Profile(setup_ms=50.0, reply_ms=40.0).slow_setup  # a slow link: every reply is as slow
    assert not Profile(setup_ms=0.4, reply_ms=0.02).slow_setup  # the reference server


def test_a_backlog_no_deeper_than_the_pipelining_turns_it_off() -> None:
    assert Profile(backlog=2).small_backlog and "no pipelining" in Profile(backlog=2).describe()
    assert not Profile(backlog=5).small_backlog  # accept-once, the emulator: the kernel's backlog holds them
    assert not Profile().small_backlog  # a target that turns newcomers away: no backlog measured


def test_a_dead_second_port_is_named_by_its_flag(server: FinEndsSession, tmp_path: Path) -> None:
    """Issue 32: the start blamed --second-port for the --target port; now each port by its own flag."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        dead = s.getsockname()[1]
    opts = Options("127.0.0.1", server.port, dead, duration=1.0, seed=1, out=tmp_path / "o", deadline=0.5)
    campaign = Campaign(opts)
    try:
        with pytest.raises(HarnessError, match=rf"nothing listening on 127.0.0.1:{dead} \(--second-port\)"):
            campaign.run()
    finally:
        campaign.close()
