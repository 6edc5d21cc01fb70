"""Each zoo member on the wire: what a client sees through it, in front of one reference server (--upstream).

The timings a test needs to observe (a release window, a status delay, a hang) are set wide or short on the command
line so that a loaded machine cannot blur them; the members' defaults run in tests/zoo/test_conformance.py.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
import socket
import struct
import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from pltf.harness import launch
from pltf.spec.codec import TelegramDecoder, build, encode
from pltf.spec.telegram import Telegram
from tests.emulator_gate import emulator_or_skip

STATUS = encode(build("request", "CMD_GET_STATUS"))
POSITION = encode(build("request", "CMD_GET_POSITION"))


@pytest.fixture(scope="module")
def upstream() -> Iterator[launch.Launched]:
    with launch.reference(time_scale=10.0) as server:
        yield server


@contextmanager
def member(upstream: launch.Launched, name: str, *extra: str) -> Iterator[launch.Launched]:
    a, b = upstream.ports
    with launch.Launched(
        launch.python("pltf.zoo", name, "--upstream", f"127.0.0.1:{a},{b}", *extra), name=f"zoo {name}"
    ) as z:
        yield z


def connect(z: launch.Launched, index: int = 0, timeout: float = 5.0) -> socket.socket:
    s = socket.create_connection(("127.0.0.1", z.ports[index]), timeout=timeout)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return s


def replies(s: socket.socket, n: int = 1, timeout: float = 5.0) -> list[Telegram]:
    """The next ``n`` replies (AssertionError at EOF or on timeout)."""
    dec, out = TelegramDecoder("reply"), []
    s.settimeout(timeout)
    while len(out) < n:
        data = s.recv(65536)
        assert data, f"closed after {len(out)} of {n} replies"
        dec.receive_data(data)
        out += list(dec)
    return out


def turned_away(s: socket.socket, within: float = 2.0) -> str:
    """'fin' or 'rst' when the target closed the connection without a byte, '' when it stayed open."""
    s.settimeout(within)
    try:
        data = s.recv(100)
    except ConnectionResetError:
        return "rst"
    except TimeoutError:
        return ""
    assert data == b"", f"a turned-away client got bytes: {data.hex()}"
    return "fin"


def newcomer(z: launch.Launched) -> str:
    """What a new client meets: 'fin' or 'rst' (turned away; a reset may end the connect itself), '' (kept)."""
    try:
        with connect(z) as s:
            return turned_away(s)
    except ConnectionResetError:
        return "rst"


def served(z: launch.Launched, within: float) -> tuple[float, int]:
    """Seconds until a newcomer is served (its GET_STATUS answered) and how many were turned away meanwhile;
    AssertionError after ``within``."""
    t0, away = time.monotonic(), 0
    while time.monotonic() - t0 < within:
        try:
            with connect(z) as s:
                s.sendall(STATUS)
                replies(s, timeout=1.0)
                return time.monotonic() - t0, away
        except (AssertionError, ConnectionResetError, ConnectionRefusedError, BrokenPipeError):
            away += 1
            time.sleep(0.002)
    raise AssertionError(f"no newcomer served within {within} s")


def test_faithful_passes_every_byte_on_both_ports(upstream: launch.Launched) -> None:
    with member(upstream, "faithful") as z, connect(z, 0) as a, connect(z, 1) as b:
        for i in range(1, len(STATUS)):  # split anywhere
            a.sendall(STATUS[:i])
            time.sleep(0.001)
            a.sendall(STATUS[i:])
        assert [t.NAME for t in replies(a, len(STATUS) - 1)] == ["CMD_GET_STATUS"] * (len(STATUS) - 1)
        b.sendall(POSITION + STATUS)
        assert [t.NAME for t in replies(b, 2)] == ["CMD_GET_POSITION", "CMD_GET_STATUS"]


@pytest.mark.parametrize(("name", "how"), [("slow-release", "fin"), ("slow-release-rst", "rst")])
def test_slow_release_turns_newcomers_away_until_the_window_ends(
    upstream: launch.Launched, name: str, how: str
) -> None:
    with member(upstream, name, "--release-ms", "600,600") as z:
        first = connect(z)
        first.sendall(STATUS)
        replies(first)
        assert newcomer(z) == how  # busy: turned away at once
        first.close()
        time.sleep(0.1)  # the client has left; the port is not free before 600 ms
        assert newcomer(z) == how
        wait, _ = served(z, within=5.0)
        assert wait >= 0.3, f"served {wait:.2f} s after the turn-away, inside the 600 ms window"


def test_slow_release_refuse_stops_listening_until_the_window_ends(upstream: launch.Launched) -> None:
    with member(upstream, "slow-release", "--turn-away", "refuse", "--release-ms", "600,600") as z:
        first = connect(z)
        first.sendall(STATUS)
        replies(first)
        with pytest.raises(ConnectionRefusedError):  # busy: the port does not listen
            connect(z)
        first.close()
        time.sleep(0.1)
        with pytest.raises(ConnectionRefusedError):  # left, but inside the release window
            connect(z)
        wait, _ = served(z, within=5.0)
        assert wait >= 0.3, f"served {wait:.2f} s after the refusal, inside the 600 ms window"
        with connect(z, 1) as other:  # the other port is not affected
            other.sendall(STATUS)
            replies(other)


def test_the_member_counts_served_and_turned_away_clients(upstream: launch.Launched, tmp_path: Path) -> None:
    stats = tmp_path / "stats.json"
    with member(upstream, "slow-release", "--release-ms", "600,600", "--stats", str(stats)) as z:
        with connect(z) as first:
            first.sendall(STATUS)
            replies(first)
            assert newcomer(z) == "fin"
            assert newcomer(z) == "fin"
        with connect(z, 1) as other:
            other.sendall(STATUS)
            replies(other)
    assert json.loads(stats.read_text()) == {"served": [1, 1], "turned_away": [2, 0]}


def test_slow_release_defaults_free_the_port_within_milliseconds(upstream: launch.Launched) -> None:
    with member(upstream, "slow-release") as z:
        rounds = [served(z, within=3.0) for _ in range(5)]  # each newcomer right after the one before left
    assert all(wait < 2.0 for wait, _ in rounds), rounds
    assert sum(away for _, away in rounds) >= 1, f"no newcomer met the release window: {rounds}"


def test_accept_once_keeps_a_newcomer_waiting_in_the_backlog(upstream: launch.Launched) -> None:
    with member(upstream, "accept-once") as z:
        first = connect(z)
        first.sendall(STATUS)
        replies(first)
        waiting = connect(z)  # the handshake completes: the kernel keeps it in the listen backlog
        waiting.sendall(STATUS)
        assert turned_away(waiting, within=0.8) == "", "a newcomer was closed instead of waiting"
        first.close()
        assert [t.NAME for t in replies(waiting)] == ["CMD_GET_STATUS"]  # its turn: the request it sent is served
        waiting.close()


def test_slow_link_replies_late(upstream: launch.Launched) -> None:
    with member(upstream, "slow-link") as z, connect(z) as s:
        for _ in range(5):
            t0 = time.monotonic()
            s.sendall(STATUS)
            replies(s)
            assert time.monotonic() - t0 >= 0.05


def _capture(port: int, out: Path) -> subprocess.Popen[bytes]:
    with (out.parent / "dumpcap.log").open("wb") as log:
        return subprocess.Popen(
            ["dumpcap", "-q", "-i", "lo", "-f", f"tcp src port {port}", "-w", str(out)],
            stdout=subprocess.DEVNULL,
            stderr=log,
        )


def _new_data(segments: list[tuple[int, ...]]) -> list[int]:
    """The lengths of the segments that carry new bytes, in capture order: (relative seq, len) rows of tshark, a
    retransmission left out (a clean-clone run at load 10 captured 24,626 bytes for six replies of 2,740)."""
    sizes, upto = [], 0
    for seq, n in segments:
        if n > 0 and seq + n > upto:
            sizes.append(seq + n - max(seq, upto))
            upto = seq + n
    return sizes


def test_slow_link_tears_and_coalesces_replies_on_the_wire(upstream: launch.Launched, tmp_path: Path) -> None:
    if not (shutil.which("dumpcap") and shutil.which("tshark")):
        pytest.skip("tshark/dumpcap not installed (apt-get install tshark)")
    pcap = tmp_path / "slow-link.pcapng"
    with member(upstream, "slow-link", "--seed", "3") as z:
        cap = _capture(z.ports[0], pcap)
        time.sleep(1.5)  # dumpcap is listening
        if cap.poll() is not None:
            pytest.skip(f"no capture on lo: {(tmp_path / 'dumpcap.log').read_text(errors='replace')[:200]}")
        with connect(z) as s:
            s.sendall(STATUS * 6)  # pipelined: six replies in flight at once
            got = replies(s, 6)
        time.sleep(0.5)
        cap.terminate()
        cap.wait(10)
    rows = subprocess.run(
        ["tshark", "-r", str(pcap), "-T", "fields", "-e", "tcp.seq", "-e", "tcp.len"],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    ).stdout.splitlines()
    sizes = _new_data([tuple(map(int, r.split())) for r in rows if r.strip()])
    frame = len(encode(got[0]))
    assert sum(sizes) == 6 * frame
    assert sizes[0] <= 7 and sum(n <= 7 for n in sizes) >= 8, f"replies not torn into small segments: {sizes}"
    ends, offsets = {frame * k for k in range(1, 6)}, []
    pos = 0
    for n in sizes:
        offsets.append((pos, pos + n))
        pos += n
    crossing = [(a, b) for a, b in offsets if any(a < e < b for e in ends)]
    assert crossing, f"no TCP segment carries the end of one reply and the start of the next: {sizes}"


def test_slow_status_holds_status_replies_only(upstream: launch.Launched) -> None:
    with member(upstream, "slow-status", "--status-delay", "1.5") as z, connect(z) as s:
        t0 = time.monotonic()
        s.sendall(POSITION)
        replies(s)
        assert time.monotonic() - t0 < 1.0
        s.sendall(STATUS + POSITION)
        got = replies(s, 2, timeout=10.0)
        assert [t.NAME for t in got] == ["CMD_GET_STATUS", "CMD_GET_POSITION"]  # in order: the position waited
        assert time.monotonic() - t0 >= 1.5


def _prelude(mode: int | None = None) -> bytes:
    names = ["CMD_CONNECT_TO_PLTF", "CMD_INIT_PLTF"]
    out = b"".join(encode(build("request", n)) for n in names)
    if mode is not None:
        out += encode(build("request", "CMD_SET_MODE", mode=mode))
    return out + encode(build("request", "CMD_START"))


MOVE = encode(build("request", "CMD_MOVE_REL", x=400, y=0, angle=0))


def test_crash_after_start_dies_behind_its_prelude_only(upstream: launch.Launched) -> None:
    with member(upstream, "crash-after-start") as z:
        with connect(z) as s:
            s.sendall(MOVE + STATUS)  # no prelude: refused by the target, nothing happens
            replies(s)
            s.sendall(_prelude(mode=4) + MOVE + STATUS)  # mode Automatic takes path commands
            replies(s)
        assert z.alive()
        with connect(z) as s:
            s.sendall(
                encode(build("request", "CMD_STOP"))
                + encode(build("request", "CMD_SET_MODE", mode=0))
                + encode(build("request", "CMD_START"))
                + MOVE
                + STATUS
            )
            assert turned_away(s) in ("fin", "rst")  # died: the connection ends without a reply
        assert z.proc is not None and z.proc.wait(5) == 134
        assert any("crash: CMD_MOVE_REL in running" in line for line in z.output)
        with pytest.raises(ConnectionRefusedError):
            connect(z)
    assert upstream.alive()  # not the member's: it stays


def test_a_bug_planted_in_another_member_fires_behind_its_wire_behaviour(upstream: launch.Launched) -> None:
    wheel = encode(build("request", "CMD_MOVE_VEL_WHEEL", vel_right=0, vel_left=-(1 << 30)))
    with member(upstream, "slow-release", "--bug", "crash-in-velocity-mode") as z:
        with connect(z) as s:
            s.sendall(encode(build("request", "CMD_STOP")) + _prelude(mode=3) + wheel + STATUS)
            assert turned_away(s) in ("fin", "rst")
        assert z.proc is not None and z.proc.wait(5) == 134
        assert any("crash: CMD_MOVE_VEL_WHEEL" in line for line in z.output)


def test_hang_unknown_key_stops_every_port(upstream: launch.Launched) -> None:
    with member(upstream, "hang-unknown-key", "--hang-seconds", "4") as z, connect(z) as s:
        s.sendall(encode(build("request", "CMD_SET_PLTF_PARAM", key="IpoTransVel", value="500")) + STATUS)
        replies(s)
        s.sendall(encode(build("request", "CMD_SET_PLTF_PARAM", key="NoSuchKey", value="1")) + STATUS)
        assert turned_away(s, within=1.0) == ""  # no reply, no close: stuck
        with connect(z, 1) as other:  # the other port: accepted by the kernel, answered by nobody
            other.sendall(STATUS)
            assert turned_away(other, within=1.0) == ""
        assert z.alive()
        assert z.proc is not None and z.proc.wait(10) == 3


def _rss_kib(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise AssertionError("no VmRSS")


def test_leak_grows_with_every_request_and_dies_at_its_limit(upstream: launch.Launched) -> None:
    with member(upstream, "leak", "--leak-kb", "1024", "--leak-limit-mb", "24") as z, connect(z) as s:
        assert z.pid is not None
        s.sendall(STATUS)
        replies(s)
        before = _rss_kib(z.pid)
        s.sendall(STATUS * 16)
        replies(s, 16)
        grown = _rss_kib(z.pid) - before
        assert grown >= 12 * 1024, f"RSS grew {grown} KiB over 16 requests of 1 MiB each"
        s.sendall(STATUS * 10)
        with pytest.raises(AssertionError, match="closed"):
            replies(s, 10)
        assert z.proc is not None and z.proc.wait(5) == 134
        assert any("out of memory: 24 MiB leaked after 24 requests" in line for line in z.output)


def test_the_member_tells_its_ports_and_upstream(upstream: launch.Launched) -> None:
    with member(upstream, "faithful") as z:
        assert sum("server started at port" in line for line in z.output) == 2


def _first_reply_after_connect(z: launch.Launched, index: int) -> tuple[socket.socket, float]:
    s = connect(z, index)
    t0 = time.monotonic()
    s.sendall(POSITION)
    replies(s)
    return s, time.monotonic() - t0


def test_slow_accept_serves_a_newcomer_at_the_timers_next_tick(upstream: launch.Launched) -> None:
    # a 1 s timer: the handshake completes at once (the kernel's backlog), the first reply waits for the tick;
    # a newcomer right after a tick waits most of a period (a loop late by half a second would blur it); the two
    # ports' timers tick together, and the server behind serves one client per port
    with member(upstream, "slow-accept", "--accept-every-ms", "1000") as z:
        first, _ = _first_reply_after_connect(z, 0)
        second, wait = _first_reply_after_connect(z, 1)
        assert wait > 0.5, f"served {wait * 1000:.0f} ms after the connect, before the timer's next tick"
        t0 = time.monotonic()
        first.sendall(POSITION)  # an admitted client is answered at once
        replies(first)
        assert time.monotonic() - t0 < 0.5
        first.close()
        second.close()


def test_absurd_values_rewrite_the_doubles_of_position_and_status(upstream: launch.Launched) -> None:
    _, b = upstream.ports  # the other port: the member's client on the first one is not turned away by it
    with socket.create_connection(("127.0.0.1", b), timeout=5) as direct:
        direct.sendall(POSITION)
        [plain] = replies(direct)
    with member(upstream, "absurd-values") as z, connect(z) as s:  # the default: little-endian
        s.sendall(POSITION)
        [swapped] = replies(s)
    raw = struct.Struct(">d")
    for name in ("angle", "vel_trans", "vel_rot"):  # the platform stands: the same pose, each double reversed
        assert raw.pack(getattr(swapped, name)) == raw.pack(getattr(plain, name))[::-1]
    with member(upstream, "absurd-values", "--absurd", "nan") as z, connect(z) as s:  # inf: test_values.py
        s.sendall(POSITION + STATUS)
        pos, status = replies(s, 2)
    assert (pos.x, pos.y) == (plain.x, plain.y)
    doubles = (pos.angle, pos.vel_trans, pos.vel_rot, status.gps_latitude, status.gps_longitude)
    assert all(math.isnan(v) for v in doubles)


def _until_closed(s: socket.socket, within: float = 5.0) -> tuple[bytes, str]:
    """What came before the close, and how it closed: 'fin', 'rst' or '' (still open after ``within``)."""
    s.settimeout(within)
    got = b""
    try:
        while data := s.recv(65536):
            got += data
    except ConnectionResetError:
        return got, "rst"
    except TimeoutError:
        return got, ""
    return got, "fin"


def test_fin_ends_session_loses_the_replies_owed_at_the_clients_fin(upstream: launch.Launched) -> None:
    with member(upstream, "fin-ends-session") as z, connect(z) as s:
        s.sendall(STATUS)
        replies(s)  # answered while the client's write half is open
        s.setsockopt(socket.IPPROTO_TCP, socket.TCP_CORK, 1)  # the requests and our FIN in one segment: written
        s.sendall(STATUS * 3)  # apart, a loaded machine ran the relay in between and it answered them all (a clean
        s.shutdown(socket.SHUT_WR)  # clone's make test beside a CPU hog: 8,268 bytes after the FIN)
        got, how = _until_closed(s)
        assert how == "fin" and len(got) < 3 * 100, f"{len(got)} bytes after the FIN ({how})"


def test_close_rst_resets_where_it_would_close(upstream: launch.Launched) -> None:
    close_socket = encode(build("request", "CMD_CLOSE_SOCKET"))
    with member(upstream, "close-rst") as z, connect(z) as s:
        s.sendall(POSITION + close_socket)
        assert _until_closed(s)[1] == "rst"


def test_backlog_one_drops_the_syns_beyond_its_backlog(upstream: launch.Launched) -> None:
    with member(upstream, "backlog-one") as z:
        first = connect(z)
        first.sendall(POSITION)
        replies(first)
        kept, dropped = [], 0
        for _ in range(4):
            try:
                kept.append(connect(z, timeout=1.0))
            except TimeoutError:
                dropped += 1  # the SYN was dropped: the connect times out (the kernel would retry)
        assert kept and dropped, f"{len(kept)} connects completed, {dropped} timed out"
        first.close()
        kept[0].sendall(POSITION)
        assert [t.NAME for t in replies(kept[0])] == ["CMD_GET_POSITION"]  # the first in the backlog: served
        for s in kept:
            s.close()


@pytest.mark.slow  # waits by design (an idle period, a restart and its 2 s down): the default tier's budget
def test_idle_drop_closes_a_silent_client_only(upstream: launch.Launched) -> None:
    with member(upstream, "idle-drop", "--idle-seconds", "1.5") as z, connect(z) as quiet, connect(z, 1) as busy:
        t0 = time.monotonic()
        for _ in range(6):  # a request every 0.5 s keeps a client
            busy.sendall(POSITION)
            replies(busy)
            time.sleep(0.5)
        assert _until_closed(quiet, within=5.0) == (b"", "fin")
        assert time.monotonic() - t0 >= 1.5
        busy.sendall(POSITION)
        replies(busy)


def test_strict_framing_closes_at_an_unknown_command_and_lenient_framing_skips_it(upstream: launch.Launched) -> None:
    unknown = b"\xff\x01\xfe\x02\x00\x00\x00\x01\xfa"  # command 250: no such telegram
    with member(upstream, "strict-framing") as z, connect(z) as s:
        s.sendall(POSITION + unknown + POSITION)
        got, how = _until_closed(s)
        dec = TelegramDecoder("reply")
        dec.receive_data(got)
        assert [t.NAME for t in dec] == ["CMD_GET_POSITION"] and how in ("fin", "rst")
    with member(upstream, "lenient-framing") as z, connect(z) as s:  # the other reading: skipped, and on it goes
        s.sendall(POSITION + unknown + POSITION)
        assert [t.NAME for t in replies(s, 2)] == ["CMD_GET_POSITION"] * 2


def test_silent_until_connect_answers_nothing_before_connect_to_pltf(upstream: launch.Launched) -> None:
    connect_to_pltf = encode(build("request", "CMD_CONNECT_TO_PLTF"))
    with member(upstream, "silent-until-connect") as z, connect(z) as s:
        s.sendall(POSITION)
        assert _until_closed(s, within=0.8) == (b"", "")  # open, and silent
        s.sendall(connect_to_pltf + POSITION)
        assert "CMD_GET_POSITION" in [t.NAME for t in replies(s, 1)]


@pytest.mark.slow  # waits by design (an idle period, a restart and its 2 s down): the default tier's budget
def test_restarts_drop_every_connection_and_the_ports_are_gone_for_a_while(upstream: launch.Launched) -> None:
    with member(upstream, "restarts", "--restart-every", "2") as z, connect(z) as s:
        s.sendall(POSITION)
        replies(s)
        assert _until_closed(s, within=10.0)[1] in ("fin", "rst")
        t0 = time.monotonic()
        with pytest.raises(ConnectionRefusedError):  # gone ...
            connect(z)
        wait, _ = served(z, within=10.0)  # ... and back
        assert time.monotonic() - t0 >= 1.0, f"back after {wait:.2f} s"


def _back(z: launch.Launched, index: int, within: float) -> float:
    """Seconds until port ``index`` serves a newcomer again after a restart: refused meanwhile, never a connection
    accepted and then closed or left unanswered (AssertionError naming what was met)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < within:
        try:
            s = connect(z, index, timeout=1.0)
        except ConnectionRefusedError:
            time.sleep(0.05)
            continue
        with s:
            s.sendall(STATUS)
            replies(s, timeout=2.0)  # accepted: served, or the member broke its row
            return time.monotonic() - t0
    raise AssertionError(f"port {index} still refused after {within} s")


@pytest.mark.slow  # three restarts, each 2 s down: about 12 s
def test_restarts_serve_every_newcomer_again_after_each_restart(upstream: launch.Launched) -> None:
    """Each restart drops the clients held across it and then serves newcomers on both ports; before, the pumps of
    the dropped clients outlived them in the selector, the next connections' sockets reused their numbers and
    failed (epoll_ctl ENOENT: "upstream port N unreachable: [Errno 2]"), and the member accepted and closed
    newcomers after its first restart."""
    with member(upstream, "restarts", "--restart-every", "1.5") as z:
        for _ in range(3):
            held = [connect(z, i) for i in (0, 1)]
            for s in held:
                s.sendall(STATUS)
                replies(s)
            for s in held:
                with s:
                    assert _until_closed(s, within=10.0)[1] in ("fin", "rst")
            for index in (0, 1):
                _back(z, index, within=10.0)
        assert "Errno" not in "\n".join(z.output), z.output


@pytest.mark.slow  # three restarts, each 2 s down: about 12 s
def test_restarts_behind_the_target_it_serves_come_back_with_a_fresh_target_each_time() -> None:
    """--serve: each restart swaps in the spare started ahead and spawns the next. A spare spawned from a thread that
    then ended died with it (launch._pdeathsig: the parent is the thread) - after its ports were known, so the
    member's second restart led to a dead target: every newcomer accepted and closed ('upstream port N
    unreachable: [Errno 111]') for the rest of its life."""
    emulator_or_skip()
    with launch.zoo("restarts", upstream="emulator", extra=["--restart-every", "1.5"]) as z:
        for _ in range(3):
            with connect(z) as held:
                held.sendall(STATUS)
                replies(held)
                assert _until_closed(held, within=10.0)[1] in ("fin", "rst")
            assert _back(z, 0, within=10.0) < 5.0  # the ports gone for 2 s (a loaded machine: a little more)
        assert "unreachable" not in "\n".join(z.output), z.output


def _listening(pid: int) -> set[tuple[str, int]]:
    """The (address, port) of every listening TCP socket of process ``pid`` (/proc: its socket inodes in
    /proc/net/tcp and tcp6, state 0A). A connect to 127.0.0.1:PORT cannot tell: another test's server may hold
    that port number on IPv4 while the member holds it on IPv6 (seen in a clean clone's make test)."""
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        with contextlib.suppress(OSError):
            if (link := os.readlink(fd)).startswith("socket:["):
                inodes.add(link[8:-1])
    out = set()
    for table, family in (("tcp", socket.AF_INET), ("tcp6", socket.AF_INET6)):
        for line in Path(f"/proc/{pid}/net/{table}").read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] == "0A" and fields[9] in inodes:
                raw, port = fields[1].split(":")
                words = b"".join(struct.pack("<I", int(raw[i : i + 8], 16)) for i in range(0, len(raw), 8))
                out.add((socket.inet_ntop(family, words), int(port, 16)))
    return out


def test_ipv6_only_listens_on_the_ipv6_loopback_only(upstream: launch.Launched) -> None:
    with member(upstream, "ipv6-only") as z:
        assert z.host == "::1"  # announced with its ports ("server started at port N on ::1"): the launcher's address
        with socket.create_connection(("::1", z.ports[0]), timeout=5) as s:
            s.sendall(POSITION)
            replies(s)
        assert z.proc is not None
        assert _listening(z.proc.pid) == {("::1", p) for p in z.ports}
