"""Stateful testing of a live target: a Hypothesis RuleBasedStateMachine over the state chart and the documents.

Rules:
- The model is the suite's chart oracle (chart.TRANSITIONS) plus the active map, roadmap and program; every rule
  sends one command to the target and then checks CMD_GET_STATUS (operation state, initialized, motion mode) and,
  after a document command, the active document against the model.
- The machine starts from a normalised state: CMD_SHUTDOWN_PLTF (Not connected, whatever state the target was
  in), then CMD_CONNECT_TO_PLTF, CMD_INIT_PLTF and CMD_SET_MODE(NO) (Ready), and the suite's own documents, so
  that the same steps meet the same target state in every run (Hypothesis replays them to shrink); the target's
  documents are restored afterwards.
- Every step is recorded as the frame that was sent and what the model expected; when a check fails, the steps of
  that run are written as a standalone, stdlib-only Python script that replays them against any target
  (``python SCRIPT HOST PORT``). Hypothesis shrinks the failure and runs the minimal example last, so the script
  left behind is the shrunk one.
"""

from __future__ import annotations

import textwrap
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule, run_state_machine_as_test
from rich.console import Console

from pltf.conformance_tests import chart, docdata
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.target import Config
from pltf.conformance_tests.wire import Session
from pltf.spec.codec import REPLIES, build, encode
from pltf.spec.compiler import fixed_size
from pltf.spec.model import enum_classes
from pltf.spec.telegram import user_fields

# The spec's enums are built at import; mypy sees them as plain IntEnum classes without members.
MotionMode: Any = enum_classes()["MotionMode"]
MODES = sorted(MotionMode._value2member_map_)
KINDS = ("map", "roadmap", "program")


@dataclass
class Recorder:
    steps: list[tuple[str, str, dict[str, Any]]] = field(default_factory=list)

    def add(self, name: str, frame: bytes, expect: dict[str, Any]) -> None:
        self.steps.append((name, frame.hex(), expect))


def _status_layout() -> tuple[int, list[int], int]:
    """(bytes before the first group, item size of each group, bytes from the last group to 'initialized')."""
    layout = user_fields(REPLIES.CMD_GET_STATUS.DEF.reply or ())
    head, groups, tail, seen_group = 1, [], 0, False
    for f in layout:
        if f.is_group:
            groups.append(sum(fixed_size(g) or 0 for g in f.fields))
            seen_group = True
        elif f.name == "initialized":
            break
        elif seen_group:
            tail += fixed_size(f) or 0
        else:
            head += fixed_size(f) or 0
    return head, groups, tail


class PlatformMachine(RuleBasedStateMachine):
    config: Config  # set by machine_for()
    out_dir: Path
    script_path: Path | None = None

    def __init__(self) -> None:
        super().__init__()
        cfg = self.config
        self.session = _connect(cfg)
        self.rec = Recorder()
        self.state = St.NOT_CONNECTED
        self.mode = int(MotionMode.MODE_MOTION_NO)
        self.docs: dict[str, bytes] = {}
        self.saved: dict[str, Any] = {}
        self._last: tuple[str, bytes] = ("(start)", b"")

    # ---- plumbing
    def _send(self, telegram: str, /, **fields: Any) -> None:
        t = build("request", telegram, **fields)
        self.session.send(t)
        self._last = (telegram, encode(t))

    def _expect(self, *, check_mode: bool = True, **extra: Any) -> None:
        expect = {"op": int(chart.REPORTED[self.state]), "init": chart.INITIALIZED[self.state], **extra}
        if check_mode:
            expect["mode"] = int(self.mode)
        name, frame = self._last
        self.rec.add(name, frame, expect)
        s = self.session.request(build("request", "CMD_GET_STATUS"))
        got = {"op": s.operation_state, "init": s.initialized, "mode": s.motion_mode}  # type: ignore[attr-defined]
        want = {k: expect[k] for k in ("op", "init", "mode") if k in expect}
        got = {k: got[k] for k in want}
        if got != want:
            self._fail(f"after {name}: status {got}, the model expects {want}")
        if "doc" in extra:
            kind, xml = extra["doc"]
            reply = self.session.request(build("request", f"CMD_GET_{kind.upper()}"))
            if not docdata.same(reply.xml, xml):  # type: ignore[attr-defined]
                self._fail(f"after {name}: the active {kind} is not the one the model expects")

    def _fail(self, message: str) -> None:
        path = write_replay(self.rec, self.out_dir, message)
        type(self).script_path = path
        raise AssertionError(f"{message}\nreplay script: {path}")

    # ---- start and end
    @initialize()
    def normalise(self) -> None:
        for kind in KINDS:
            reply = self.session.request(build("request", f"CMD_GET_{kind.upper()}"))
            self.saved[kind] = reply
        # the motion mode survives every state: unknown until CMD_SET_MODE below
        for command in ("CMD_SHUTDOWN_PLTF", "CMD_CONNECT_TO_PLTF", "CMD_INIT_PLTF"):  # Ready: every state is near
            self._send(command)
            self.state = chart.target(self.state, command)
            self._expect(check_mode=False)
        self._chart("CMD_SET_MODE", mode=int(MotionMode.MODE_MOTION_NO))  # the same start for every run
        for kind in KINDS:
            self._set_doc(kind, docdata.valid(kind))

    def teardown(self) -> None:
        try:
            for kind, reply in self.saved.items():
                if reply.xml.strip():
                    fields = {"xml": reply.xml} if kind == "program" else {"name": reply.name, "xml": reply.xml}
                    self.session.send(build("request", f"CMD_SET_{kind.upper()}", **fields))
            self.session.request(build("request", "CMD_GET_STATUS"))
        finally:
            self.session.close()

    # ---- the chart
    def _chart(self, command: str, /, **fields: Any) -> None:
        self._send(command, **fields)
        if chart.allowed(self.state, command):
            self.state = chart.target(self.state, command)
            if command == "CMD_SET_MODE":
                self.mode = fields["mode"]
        self._expect()

    @rule(
        command=st.sampled_from(chart.CHART_COMMANDS),
        mode=st.sampled_from([m for m in MODES if m != MotionMode.MODE_MOTION_PROGRAM]),
    )
    def chart_command(self, command: str, mode: int) -> None:
        """One command of the chart (the mode is used by CMD_SET_MODE only)."""
        self._chart(command, **({"mode": mode} if command == "CMD_SET_MODE" else {}))

    # ---- documents
    def _set_doc(self, kind: str, xml: bytes, name: str = "stateful") -> None:
        text = xml.decode("latin-1")
        if kind == "program":
            self._send("CMD_SET_PROGRAM", xml=text)
        else:
            self._send(f"CMD_SET_{kind.upper()}", name=name, xml=text)
        valid = docdata.parse(xml) is not None and xml in (docdata.valid(kind), docdata.variant(kind))
        if valid:
            self.docs[kind] = xml
        self._expect(doc=(kind, self.docs[kind].decode("latin-1")))

    @rule(kind=st.sampled_from(KINDS), which=st.integers(-1, 6))
    def set_document(self, kind: str, which: int) -> None:
        """A valid document (-1: the suite's, 0: its variant) or one of the invalid ones (1..)."""
        if which <= 0:
            self._set_doc(kind, docdata.valid(kind) if which < 0 else docdata.variant(kind))
        else:
            bad = docdata.invalid(kind)
            self._set_doc(kind, bad[(which - 1) % len(bad)][1])

    @invariant()
    def connection_open(self) -> None:
        if not self.session.is_open:
            self._fail("the target closed the connection")


def _connect(cfg: Config) -> Session:
    deadline = time.monotonic() + cfg.connect_window
    while True:
        s = Session(cfg.host, cfg.port, timeout=cfg.reply_timeout)
        try:
            s.connect()
            s.request(build("request", "CMD_GET_STATUS"), timeout=1.0)
            return s
        except Exception:
            s.close()
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)


def machine_for(config: Config, out_dir: Path) -> type[PlatformMachine]:
    return type("PlatformMachineFor", (PlatformMachine,), {"config": config, "out_dir": out_dir, "script_path": None})


def run_stateful(
    config: Config,
    examples: int,
    out_dir: Path,
    console: Console | None = None,
    steps: int = 25,
    derandomize: bool = False,
) -> int:
    """Run ``examples`` random programs against the target; 0 when all pass, 1 (and a replay script) if not."""
    console = console or Console()
    machine = machine_for(config, out_dir)
    try:
        run_state_machine_as_test(
            machine,
            settings=settings(
                max_examples=examples,
                stateful_step_count=steps,
                deadline=None,
                database=None,
                derandomize=derandomize,
                suppress_health_check=list(HealthCheck),
                print_blob=False,
            ),
        )
    except AssertionError as exc:
        console.print(f"[bold red]stateful test failed:[/] {str(exc).splitlines()[0]}")
        console.print(f"replay script (shrunk): {machine.script_path}")
        return 1
    console.print(f"stateful test: {examples} examples of up to {steps} steps passed")
    return 0


# ---- the standalone replay script
_TEMPLATE = '''\
#!/usr/bin/env python3
"""Replay of a PlatformCtrl conformance failure found by the stateful test (pltf conform --stateful).

Failure: {message}

Usage: python {name} HOST PORT   (exit 0: the target behaved as the model expects, 1: it did not)
Standalone: Python 3.8+, standard library only. Each step sends one frame, then checks CMD_GET_STATUS
(operation state, initialized, motion mode) and, after a document command, the active document.
"""
import socket
import struct
import sys
import xml.etree.ElementTree as ET

STEPS = {steps!r}
STATUS_HEAD, STATUS_GROUPS, STATUS_TAIL = {head}, {groups!r}, {tail}
GET = {{"status": "ff01fe020000000112", "map": "ff01fe02000000011a", "roadmap": "ff01fe020000000121",
       "program": "ff01fe020000000129"}}


def read_frame(sock):
    def need(n):
        data = b""
        while len(data) < n:
            chunk = sock.recv(n - len(data))
            if not chunk:
                raise SystemExit("the target closed the connection")
            data += chunk
        return data
    head = need(8)
    if head[:4] != b"\\xff\\x01\\xfe\\x02":
        raise SystemExit("bad reply header " + head.hex())
    return need(struct.unpack(">I", head[4:])[0])


def status(sock):
    sock.sendall(bytes.fromhex(GET["status"]))
    data = read_frame(sock)
    pos = STATUS_HEAD
    for size in STATUS_GROUPS:
        pos += 4 + struct.unpack_from(">i", data, pos)[0] * size
    pos += STATUS_TAIL
    init, _reached, mode, op = struct.unpack_from(">BBBB", data, pos)
    return {{"op": op, "init": init, "mode": mode}}


def document(sock, kind):
    sock.sendall(bytes.fromhex(GET[kind]))
    data = read_frame(sock)
    n = struct.unpack_from(">i", data, 1)[0]
    return data[5:5 + n].decode("latin-1")


def same(a, b):
    def canon(text):
        try:
            return ET.canonicalize(xml_data=text.encode("latin-1"), strip_text=True)
        except Exception:
            return None
    return canon(a) is not None and canon(a) == canon(b)


def main():
    host, port = sys.argv[1], int(sys.argv[2])
    sock = socket.create_connection((host, port), timeout=5)
    for i, (name, frame, expect) in enumerate(STEPS):
        sock.sendall(bytes.fromhex(frame))
        got = status(sock)
        want = {{k: expect[k] for k in ("op", "init", "mode") if k in expect}}
        got = {{k: got[k] for k in want}}
        line = "step %d %s: status %s" % (i, name, got)
        if got != want:
            print(line + " - EXPECTED %s" % want)
            return 1
        if "doc" in expect:
            kind, xml = expect["doc"]
            if not same(document(sock, kind), xml):
                print(line + " - the active %s is not the expected one" % kind)
                return 1
        print(line + " ok")
    print("the target behaved as the model expects")
    return 0


if __name__ == "__main__":
    sys.exit(main())
'''


def write_replay(rec: Recorder, out_dir: Path, message: str) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "replay_stateful.py"
    head, groups, tail = _status_layout()
    steps = [(n, f, {k: (list(v) if isinstance(v, tuple) else v) for k, v in e.items()}) for n, f, e in rec.steps]
    text = _TEMPLATE.format(
        message=textwrap.shorten(message, 300), name=path.name, steps=steps, head=head, groups=groups, tail=tail
    )
    path.write_text(text, encoding="utf-8")
    return path
