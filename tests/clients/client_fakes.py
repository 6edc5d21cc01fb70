"""What the client tests share: ``FakePlatform`` (a stand-in PlatformCtrl in a thread), ``LiveServer``
(``python -m pltf.reference_server`` in a subprocess) and the frames of the field capture.

``FakePlatform`` answers GET_STATUS and GET_POSITION with frames built by spec.codec, follows the state chart's
main transitions and can be told to misbehave (hold replies back, answer in reverse order, hang up, send garbage).
"""

from __future__ import annotations

import abc
import contextlib
import math
import re
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, Self

from pltf.client import EmergencyState, MotionMode, OperationState, PlannerState
from pltf.spec.codec import REPLIES, TelegramDecoder, build, encode
from pltf.spec.telegram import Telegram, user_fields

REPO = Path(__file__).resolve().parents[2]
READY, RUNNING, BREAKED, NOT_INIT = (
    OperationState.ST_OP_READY,
    OperationState.ST_OP_RUNNING,
    OperationState.ST_OP_BREAKED,
    OperationState.ST_OP_NOT_INITIALIZED,
)
AUTOMATIC, VEL = MotionMode.MODE_MOTION_AUTOMATIC, MotionMode.MODE_MOTION_VEL


def status_telegram(**values: Any) -> Telegram:
    """A CMD_GET_STATUS reply: zeros and empty groups, then ``values``."""
    fields: dict[str, Any] = {}
    for f in user_fields(REPLIES.CMD_GET_STATUS.DEF.reply):
        if f.is_group:
            fields[f.name] = ()
        else:
            zero: Any = 0.0 if f.type == "DOUBLE" else 0
            fields[f.name] = (zero,) * f.repeat if f.repeat else zero
    fields.update(values)
    return build("reply", "CMD_GET_STATUS", **fields)


# (accepted in, leads to): the main transitions of guide 4.2 figure 2
TRANSITIONS = {
    "CMD_INIT_PLTF": ({"connected"}, READY),
    "CMD_START": ({READY}, RUNNING),
    "CMD_BREAK": ({RUNNING}, BREAKED),
    "CMD_CONTINUE": ({BREAKED}, RUNNING),
    "CMD_STOP": ({RUNNING, BREAKED}, READY),
}


class LoopbackServer(abc.ABC):
    """A TCP server on 127.0.0.1 (an ephemeral port) that serves each connection it accepts on a thread of its
    own (``_serve``). A subclass sets its own state first, then calls ``start()``; ``with`` closes it."""

    def __init__(self) -> None:
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port: int = self.listener.getsockname()[1]
        self.conns: list[socket.socket] = []
        self._threads: list[threading.Thread] = []
        self._stop = threading.Event()
        self._accepter = threading.Thread(target=self._accept, daemon=True)

    def start(self) -> None:
        self._accepter.start()

    def spawn(self, fn: Any, *args: Any) -> None:
        """Run ``fn(*args)`` on a thread that ``close()`` waits for."""
        t = threading.Thread(target=fn, args=args, daemon=True)
        self._threads.append(t)
        t.start()

    def _accept(self) -> None:
        self.listener.settimeout(0.05)  # closing a listener does not wake accept(): poll the stop flag
        while not self._stop.is_set():
            try:
                conn, _ = self.listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            conn.settimeout(None)
            self.conns.append(conn)
            self.spawn(self._serve, conn)

    @abc.abstractmethod
    def _serve(self, conn: socket.socket) -> None:
        """Serve one accepted connection (on its own thread)."""

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._stop.set()
        for conn in list(self.conns):
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)
        for t in [self._accepter, *self._threads]:
            if t.ident is not None:
                t.join(5)
        self.listener.close()
        for conn in self.conns:
            conn.close()


class FakePlatform(LoopbackServer):
    """A stand-in PlatformCtrl on 127.0.0.1: one client at a time, served by a thread.

    A move in state Running and mode Automatic is taken up like in a control loop: the first status requested
    after it still shows the planner state and target flag of the move before; from the next one the planner
    state is ``plan`` (a failure ends the move there) and the target is reached ``arrive_after`` status
    requests after the move. Each status reply's time stamp is ``stamp_step`` ms later than the one before.
    """

    def __init__(self) -> None:
        super().__init__()
        self.state: Any = NOT_INIT  # an OperationState, or "connected" (CAN up, not initialized)
        self.mode = MotionMode.MODE_MOTION_NO
        self.pose = (0, 0, 0)  # mm, mm, 1000*deg
        self.target: tuple[int, int, int] | None = None
        self.target_reached = False
        self.planner = PlannerState.PLANNER_STANDBY
        self.emergency = EmergencyState.ST_EM_NOT_ACTIVE
        self.arrive_after = 3
        self.plan = PlannerState.PLANNER_PATH_FOUND  # the planner's verdict on the next move
        self.stamp_step = 20  # ms per status reply (0: a platform whose time stamp stands still)
        self.stamp = 0
        self._taken_up = True  # the last move showed in a status
        self.received: list[Telegram] = []
        self.reply_delay = 0.0  # seconds before each reply
        self.reverse = False  # hold a reply back until the next one, then send both in reverse order
        self.garbage: bytes | None = None  # sent instead of the next reply
        self.hang_up_on: str | None = None  # close the connection on receiving this telegram
        self.disconnects = 0
        self._held: list[bytes] = []
        self.start()

    def _serve(self, conn: socket.socket) -> None:
        decoder = TelegramDecoder("request")
        with conn:
            while True:
                try:
                    data = conn.recv(65536)
                except OSError:
                    data = b""
                if not data:
                    break
                decoder.receive_data(data)
                if not self._handle_all(conn, decoder):
                    break
        self.disconnects += 1

    def _handle_all(self, conn: socket.socket, decoder: TelegramDecoder) -> bool:
        for t in decoder:
            self.received.append(t)
            if self.hang_up_on == t.NAME:
                return False
            reply = self.handle(t)
            if reply is None:
                continue
            time.sleep(self.reply_delay)
            frame = encode(reply)
            if self.garbage is not None:
                frame, self.garbage = self.garbage, None
            if self.reverse:
                self._held.append(frame)
                if len(self._held) < 2:
                    continue
                frame, self._held = b"".join(reversed(self._held)), []
            conn.sendall(frame)
        return True

    def handle(self, t: Telegram) -> Telegram | None:
        name = t.NAME
        if name == "CMD_CONNECT_TO_PLTF" and self.state == NOT_INIT:
            self.state = "connected"
        elif name in TRANSITIONS and self.state in TRANSITIONS[name][0]:
            self.state = TRANSITIONS[name][1]
        elif name == "CMD_SET_MODE" and self.state == READY:
            self.mode = MotionMode(t.mode)
        elif name in ("CMD_MOVE_ABS", "CMD_MOVE_REL") and self.state == RUNNING and self.mode == AUTOMATIC:
            x, y, a = t.x, t.y, t.angle
            if name == "CMD_MOVE_REL":
                x, y, a = self.pose[0] + x, self.pose[1] + y, self.pose[2] + a
            self.target, self.countdown, self._taken_up = (x, y, a), self.arrive_after, False
        elif name == "CMD_GET_POSITION":
            x, y, a = self.pose
            return build(
                "reply", "CMD_GET_POSITION", x=x, y=y, angle=math.radians(a / 1000), vel_trans=0.0, vel_rot=0.0
            )
        elif name == "CMD_GET_STATUS":
            self._control_period()
            reported = NOT_INIT if self.state == "connected" else self.state
            x, y, a = self.pose
            return status_telegram(
                est_x=x,
                est_y=y,
                est_angle=a,
                cmd_x=x,
                cmd_y=y,
                cmd_angle=a,
                operation_state=int(reported),
                motion_mode=int(self.mode),
                target_reached=int(self.target_reached),
                planner_state=int(self.planner),
                emergency_state=int(self.emergency),
                initialized=int(reported != NOT_INIT),
                scan=((10, -20), (30, 40)),
                ir_active=(0, 1, 0, 1),
                timestamp=self.stamp,
            )
        return None

    def _control_period(self) -> None:
        """What the platform did since the last status request (one status request: one control period)."""
        self.stamp += self.stamp_step
        if self.target is None:
            return
        if not self._taken_up:  # the first status after the move: the move before still shows
            self._taken_up = True
            return
        if self.countdown == self.arrive_after:  # the first period of the move: the planner's verdict
            self.target_reached, self.planner = False, self.plan
            if self.plan != PlannerState.PLANNER_PATH_FOUND:
                self.target = None
                return
        self.countdown -= 1
        if self.countdown <= 0:
            self.pose, self.target, self.target_reached = self.target, None, True
            self.planner = PlannerState.PLANNER_STANDBY

    def names(self) -> list[str]:
        return [t.NAME for t in self.received]


# field-evidence.md: frames captured from a 2017 C++ client (hex)
CAPTURED = [
    ("connect_to_pltf", (), "ff01fe02 00000001 00"),
    ("stop", (), "ff01fe02 00000001 0e"),
    ("continue_", (), "ff01fe02 00000001 0d"),
    ("set_mode", (VEL,), "ff01fe02 00000005 0f 00000003"),
    ("move_vel_wheel", (300, 300), "ff01fe02 00000009 17 0000012c 0000012c"),
    ("move_vel_wheel", (-300, -300), "ff01fe02 00000009 17 fffffed4 fffffed4"),
    ("move_rel", (1000, 0, 0), "ff01fe02 0000000d 16 000003e8 00000000 00000000"),
]


STARTED = re.compile(r"server started at port (\d+)")


class LiveServer:
    """``python -m pltf.reference_server`` on two free ports, ready once both listen and the start-up is logged.

    ``time_scale``: simulated seconds per wall second; ``args``: more options of the server.
    """

    def __init__(self, data_dir: Path, log_path: Path, time_scale: float = 20.0, *args: str) -> None:
        self.log_path = log_path
        self.time_scale = time_scale
        self._log = log_path.open("wb")
        cmd = [
            sys.executable,
            "-m",
            "pltf.reference_server",
            "--ports",
            "0,0",
            "--data-dir",
            str(data_dir),
            "--time-scale",
            f"{time_scale:g}",
            "--seed",
            "1",
            *args,
        ]
        self.proc = subprocess.Popen(cmd, cwd=REPO, stdout=self._log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 30
        while len(ports := STARTED.findall(self.log())) < 2 or "system state" not in self.log():
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.close()
                raise AssertionError(f"reference server did not start:\n{self.log()}")
            time.sleep(0.05)
        self.ports = [int(p) for p in ports]

    def log(self) -> str:
        return self.log_path.read_text(encoding="utf-8", errors="replace")

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._log.close()
