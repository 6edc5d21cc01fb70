"""The one launcher: start a PlatformCtrl target as a child process on ephemeral ports and read its ports.

Every tool that needs a target of its own uses this module: the conformance suite and its tests (the reference
server, a mutant), the fuzzer (any command, restarted for every reproduction), the differential mode, the
benchmarks, and the zoo itself (a member starts the server behind it).

Rules:
- A target is a command line. ``Launched(argv)`` takes a list; ``Launcher(template, host, port, second_port)``
  takes the fuzzer's template string: ``{port}``, ``{second_port}`` and ``{ports}`` ("A,B") come from the
  address, ``{tmpdir}`` is a fresh empty directory per start.
- Port 0 asks for ephemeral ports: the target logs ``server started at port N`` (the reference server, the
  zoo; the emulator prefixes ``emulator:``) once per port, in port order, and we read them from its merged
  stdout/stderr. A target that listens elsewhere than ``host`` says so: ``server started at port N on ::1``
  (the zoo's IPv6-only member); the harness then talks to that address. The output goes to a log file (no
  reader thread, no pipe to fill); ``output`` is its tail.
- The child runs in a session (process group) of its own, so ``stop`` ends the target and whatever it started
  itself (a zoo member's server) and nothing else: SIGTERM to the group, SIGKILL after a grace period. It also
  gets SIGTERM when the thread that started it ends (PR_SET_PDEATHSIG): no target outlives its harness.
- Every wait is bounded. A start that fails raises ``LaunchError`` with the command and the output's tail.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import IO

from pltf.fixtures import seed_data_dir
from pltf.harness.ports import free_ports

STARTED = re.compile(r"(?:server|emulator) started at port (\d+)")
ANNOUNCED_HOST = re.compile(r"(?:server|emulator) started at port \d+ on (\S+)")
START_TIMEOUT = 30.0  # a loaded machine imports numpy and scipy slowly
REPO = Path(__file__).resolve().parents[1]


class LaunchError(RuntimeError):
    """The target could not be started (the harness's problem: exit status 2)."""


class Launched:
    """One target process; ``start`` may be called again after ``stop`` (a fresh instance each time)."""

    def __init__(
        self,
        argv: Sequence[str] = (),
        *,
        host: str = "127.0.0.1",
        ports: tuple[int, int] = (0, 0),
        name: str = "",
        env: dict[str, str] | None = None,
        start_timeout: float = START_TIMEOUT,
        new_session: bool = True,
    ) -> None:
        self.argv = list(argv)
        self.host = host
        self.want = ports
        self.ports: tuple[int, int] = ports
        self.name = name or (Path(self.argv[0]).name if self.argv else "target")
        self.env = env
        self.start_timeout = start_timeout
        self.new_session = new_session
        self.proc: subprocess.Popen[bytes] | None = None
        self.starts = 0
        self._log: IO[bytes] | None = None
        self._tmp: str | None = None

    # ---- what to run
    def command(self) -> list[str]:
        """The command line of the next start (``self._tmp`` is its fresh directory)."""
        return list(self.argv)

    # ---- life cycle
    def start(self) -> tuple[int, int]:
        """A fresh instance; its ports once it serves them."""
        self.cleanup()
        self._spawn()
        return self._ready()

    def begin(self) -> None:
        """A fresh instance, not waited for: ``ports_when_ready`` reads its ports later (a spare started ahead)."""
        self.cleanup()
        self._spawn()

    def ports_when_ready(self) -> tuple[int, int]:
        """The ports of the instance ``begin`` started, once it serves them (LaunchError when it does not)."""
        return self._ready()

    def _spawn(self) -> None:
        self._tmp = tempfile.mkdtemp(prefix="pltf-target-")
        self._log = tempfile.NamedTemporaryFile(prefix="pltf-target-", suffix=".log", delete=False)  # noqa: SIM115
        argv = self.command()
        env = dict(os.environ, PYTHONUNBUFFERED="1", **(self.env or {}))
        try:
            self.proc = subprocess.Popen(
                argv,
                stdout=self._log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
                env=env,
                start_new_session=self.new_session,
                preexec_fn=_die_with_parent,  # noqa: PLW1509 (see _pdeathsig)
            )
        except OSError as exc:
            self.cleanup()
            raise LaunchError(f"cannot start {self.name} ({shlex.join(argv)}): {exc}") from None

    def _ready(self) -> tuple[int, int]:
        self.starts += 1
        try:
            self.ports = self._await_ports() if 0 in self.want else self._await_listening()
        except LaunchError:
            self.stop()
            raise
        return self.ports

    def _await_ports(self) -> tuple[int, int]:
        deadline = time.monotonic() + self.start_timeout
        seen: list[int] = []
        while len(seen) < 2 and self.alive() and time.monotonic() < deadline:
            time.sleep(0.02)
            seen = [int(m) for m in STARTED.findall(self._read_log())]
        if len(seen) < 2:
            seen = [int(m) for m in STARTED.findall(self._read_log())]
        self._learn_host()
        if len(seen) < 2:
            why = "exited" if not self.alive() else f"did not report two ports within {self.start_timeout:g} s"
            raise LaunchError(
                f"{self.name} {why} ('server started at port N' expected; "
                f"{shlex.join(self.command_line)}): {' | '.join(self.output[-8:])}"
            )
        return seen[0], seen[1]

    def _learn_host(self) -> None:
        """The address the target announced with its ports, if it named one."""
        if found := ANNOUNCED_HOST.findall(self._read_log()):
            self.host = found[0]

    def _await_listening(self) -> tuple[int, int]:
        deadline = time.monotonic() + self.start_timeout
        while time.monotonic() < deadline and self.alive():
            self._learn_host()
            try:
                socket.create_connection((self.host, self.want[1]), timeout=0.5).close()
                return self.want
            except OSError:
                time.sleep(0.05)
        raise LaunchError(f"{self.name} does not listen on {self.host}:{self.want[1]}: {' | '.join(self.output[-8:])}")

    @property
    def command_line(self) -> list[str]:
        return list(self.proc.args) if self.proc is not None else self.command()  # type: ignore[arg-type]

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def exit_code(self) -> int | None:
        return None if self.proc is None else self.proc.poll()

    @property
    def pid(self) -> int | None:
        return None if self.proc is None else self.proc.pid

    def stop(self, grace: float = 3.0) -> int | None:
        """End the target (and its process group); its exit status, None when none was started."""
        proc, self.proc = self.proc, None
        if proc is None:
            return None
        if proc.poll() is None:
            self._signal(proc, signal.SIGTERM)
            deadline = time.monotonic() + grace
            while not _exited(proc.pid) and time.monotonic() < deadline:
                time.sleep(0.01)
            # the leader is alive or a zombie (not reaped yet), so its group id is still ours: end what is left
            self._signal(proc, signal.SIGKILL)
            proc.wait(5)
        elif self.new_session:  # died by itself; its group may hold what it started (ESRCH when empty)
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGKILL)
        if self._tmp is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None
        return proc.returncode

    def _signal(self, proc: subprocess.Popen[bytes], sig: int) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            if self.new_session:
                os.killpg(proc.pid, sig)
            else:
                proc.send_signal(sig)

    def cleanup(self) -> None:
        """Stop the target and remove its log."""
        self.stop()
        if self._log is not None:
            self._log.close()
            Path(self._log.name).unlink(missing_ok=True)
            self._log = None

    def __enter__(self) -> Launched:
        if self.proc is None:
            self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.cleanup()

    # ---- output
    def _read_log(self, limit: int = 1 << 20) -> str:
        if self._log is None:
            return ""
        with open(self._log.name, "rb") as fh:
            fh.seek(0, 2)
            size = fh.tell()
            fh.seek(max(0, size - limit))
            return fh.read().decode("utf-8", "replace")

    @property
    def output(self) -> list[str]:
        """The last lines the target wrote (stdout and stderr)."""
        return self._read_log(1 << 16).splitlines()[-200:]

    @property
    def log_lines(self) -> list[str]:
        return self.output

    @property
    def tmpdir(self) -> Path:
        """The fresh directory of the current start."""
        assert self._tmp is not None, "not started"
        return Path(self._tmp)


class Launcher(Launched):
    """The fuzzer's form: a command template (see the module rules) for ``host`` and the two ports.

    Warm spares (``spares = True``, ephemeral ports only): while one instance is in use the next one starts, so a
    minimiser that wants a fresh instance per test waits for a start only when the spare is not up yet. A spare
    not taken is stopped with ``no_spares`` or ``cleanup``."""

    def __init__(self, template: str, host: str, port: int, second_port: int) -> None:
        super().__init__(host=host, ports=(port, second_port), name=shlex.split(template)[0] if template else "")
        self.template = template
        self.spares = False
        self._spare: Launcher | None = None

    def command(self) -> list[str]:
        a, b = self.want
        return shlex.split(self.template.format(port=a, second_port=b, ports=f"{a},{b}", tmpdir=self._tmp or ""))

    def start(self) -> tuple[int, int]:
        spare, self._spare = self._spare, None
        self.cleanup()
        if spare is not None and spare.alive():  # adopt it: its process, log and directory are ours now
            self.proc, self._log, self._tmp = spare.proc, spare._log, spare._tmp
        else:
            if spare is not None:
                spare.cleanup()
            self._spawn()
        try:
            return self._ready()
        finally:
            if self.spares and 0 in self.want:
                self._spare = Launcher(self.template, self.host, *self.want)
                self._spare._spawn()

    def no_spares(self) -> None:
        self.spares = False
        if self._spare is not None:
            spare, self._spare = self._spare, None
            spare.cleanup()

    def cleanup(self) -> None:
        """Stop the instance in use and the spare; remove their logs (``start`` takes the spare out first)."""
        super().cleanup()
        if self._spare is not None:
            self._spare.cleanup()
            self._spare = None


class _DataDirTarget(Launched):
    """A target whose data directory is ``{tmpdir}/data`` unless one is given."""

    def __init__(self, argv: Sequence[str], data_dir: str | Path | None, *, ports: tuple[int, int], name: str) -> None:
        super().__init__(argv, ports=ports, name=name)
        self.data_dir = Path(data_dir) if data_dir is not None else None

    def data(self) -> Path:
        return self.data_dir if self.data_dir is not None else self.tmpdir / "data"

    def command(self) -> list[str]:
        return [a.replace("{data}", str(self.data())) for a in self.argv]


def _pdeathsig() -> Callable[[], None] | None:
    """In the child before exec: SIGTERM when the thread that started it ends (Linux PR_SET_PDEATHSIG), so a
    target outlives no harness, even one killed without its clean-up (a timeout, SIGKILL). The C function is
    looked up here, in the parent: the child only calls it (no import, no lock taken between fork and exec)."""
    if not sys.platform.startswith("linux"):
        return None
    prctl = ctypes.CDLL(None, use_errno=True).prctl
    return lambda: prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG = 1


_die_with_parent = _pdeathsig()


def _exited(pid: int) -> bool:
    """Has child ``pid`` exited? (Without reaping it: a zombie keeps its process group id reserved.)"""
    try:
        return os.waitid(os.P_PID, pid, os.WEXITED | os.WNOHANG | os.WNOWAIT) is not None
    except ChildProcessError:
        return True


def python(module: str, *args: str) -> list[str]:
    return [sys.executable, "-m", module, *args]


def reference(
    *,
    time_scale: float = 10.0,
    seed: int = 1,
    data_dir: str | Path | None = None,
    extra: Sequence[str] = (),
    mutant: str | None = None,
    ports: tuple[int, int] = (0, 0),
    log_level: str = "INFO",
    start_timeout: float = START_TIMEOUT,
) -> _DataDirTarget:
    """The reference server (or a model mutant of it: conformance_tests/mutants/patches.py). Below INFO it does
    not log the ports it took, so a quiet one gets two free ports chosen here."""
    if log_level not in ("DEBUG", "INFO") and 0 in ports:
        ports = free_ports()
    args = [*_server_args(ports, time_scale, seed), "--log-level", log_level, *extra]
    argv = (
        python("pltf.conformance_tests.mutants.serve", mutant, *args)
        if mutant
        else python("pltf.reference_server", *args)
    )
    target = _DataDirTarget(argv, data_dir, ports=ports, name=f"mutant {mutant}" if mutant else "reference server")
    target.start_timeout = start_timeout
    return target


def _server_args(ports: tuple[int, int], time_scale: float, seed: int) -> list[str]:
    """The options the reference server and the emulator share: ports, data directory ({data}), time scale, seed."""
    return [
        "--ports",
        f"{ports[0]},{ports[1]}",
        "--data-dir",
        "{data}",
        "--time-scale",
        f"{time_scale:g}",
        "--seed",
        str(seed),
    ]


def emulator_binary() -> Path | None:
    """The Go emulator's binary: $PLTF_EMULATOR, else emulator/bin/emulator of this checkout (built with
    emulator/build.sh when missing and Go is installed); None when there is none."""
    given = os.environ.get("PLTF_EMULATOR")
    if given:
        return Path(given) if Path(given).is_file() else None
    binary = REPO / "emulator" / "bin" / "emulator"
    if binary.is_file():
        return binary
    build = REPO / "emulator" / "build.sh"
    if build.is_file() and shutil.which("go"):
        done = subprocess.run(["sh", str(build)], capture_output=True, text=True, timeout=600, check=False)
        if done.returncode == 0 and binary.is_file():
            return binary
    return None


def why_no_emulator() -> str:
    if os.environ.get("PLTF_EMULATOR"):
        return f"PLTF_EMULATOR={os.environ['PLTF_EMULATOR']} is not a file"
    if not (REPO / "emulator" / "build.sh").is_file():
        return f"no emulator/ in this checkout ({REPO}); set PLTF_EMULATOR to its binary"
    if not shutil.which("go"):
        return "the emulator is not built and Go is not installed (sh emulator/build.sh needs Go 1.22+)"
    return "sh emulator/build.sh failed (run it to see why)"


class _Emulator(_DataDirTarget):
    def command(self) -> list[str]:
        data = self.data()
        if not data.exists():  # the same disk the reference server starts with (fixtures/)
            seed_data_dir(data)
        return super().command()


def emulator(
    *,
    time_scale: float = 10.0,
    seed: int = 1,
    data_dir: str | Path | None = None,
    extra: Sequence[str] = (),
    ports: tuple[int, int] = (0, 0),
) -> _DataDirTarget:
    """The Go emulator (emulator/, issue 17); LaunchError when it is not there (``why_no_emulator``)."""
    binary = emulator_binary()
    if binary is None:
        raise LaunchError(f"the emulator is not available: {why_no_emulator()}")
    argv = [str(binary), *_server_args(ports, time_scale, seed), *extra]
    return _Emulator(argv, data_dir, ports=ports, name="emulator")


def zoo(
    member: str,
    *,
    upstream: str = "reference",
    time_scale: float = 10.0,
    seed: int = 1,
    extra: Sequence[str] = (),
    ports: tuple[int, int] = (0, 0),
) -> Launched:
    """A zoo member (``python -m pltf.zoo``) in front of the reference server or the emulator it starts."""
    argv = python(
        "pltf.zoo",
        member,
        "--serve",
        upstream,
        "--ports",
        f"{ports[0]},{ports[1]}",
        "--time-scale",
        f"{time_scale:g}",
        "--seed",
        str(seed),
        *extra,
    )
    return Launched(argv, ports=ports, name=f"zoo {member} ({upstream})")  # a member on ::1 announces it


def target(kind: str, **kw: object) -> Launched:
    """``reference``, ``emulator``, ``mutant:PATCH`` or ``zoo:MEMBER[@emulator]`` (a table for tests and the CLI)."""
    head, _, rest = kind.partition(":")
    if head == "reference":
        return reference(**kw)  # type: ignore[arg-type]
    if head == "emulator":
        return emulator(**kw)  # type: ignore[arg-type]
    if head == "mutant" and rest:
        return reference(mutant=rest, **kw)  # type: ignore[arg-type]
    if head == "zoo" and rest:
        member, _, upstream = rest.partition("@")
        return zoo(member, upstream=upstream or "reference", **kw)  # type: ignore[arg-type]
    raise LaunchError(f"unknown target kind {kind!r} (reference, emulator, mutant:PATCH, zoo:MEMBER[@emulator])")
