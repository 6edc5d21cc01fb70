"""launch.py, the one launcher: ports read from the target's log, a process group ended as a whole, the template
form with a fresh directory per start and warm spares, clear errors, and no target outliving its harness."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pltf.harness import launch
from tests.emulator_gate import emulator_or_skip

# a target that starts in milliseconds: two listening ports, the reference server's log line, serves nothing
TINY = (
    "import socket,sys,time,os\n"
    "ls=[socket.create_server(('127.0.0.1',0)) for _ in range(2)]\n"
    "[print(f'tiny: server started at port {s.getsockname()[1]}', flush=True) for s in ls]\n"
    "print('dir', sys.argv[1:], flush=True)\n"
    "time.sleep(120)\n"
)


def refused(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=1.0).close()
    except ConnectionRefusedError:
        return True
    return False


def gone(pid: int, within: float = 10.0) -> bool:
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.05)
    return False


def tiny(tmp_path: Path) -> str:
    script = tmp_path / "tiny.py"
    script.write_text(TINY, encoding="utf-8")
    return f"{sys.executable} {script} {{tmpdir}} {{ports}}"


def test_the_template_form_reads_the_ports_and_gives_each_start_a_fresh_directory(tmp_path: Path) -> None:
    target = launch.Launcher(tiny(tmp_path), "127.0.0.1", 0, 0)
    try:
        first = target.start()
        assert all(p > 0 for p in first) and not refused(first[0])
        dir1 = target.tmpdir
        assert any(str(dir1) in line and "0,0" in line for line in target.output)
        second = target.start()
        assert target.tmpdir != dir1 and not dir1.exists()  # the first instance and its directory are gone
        assert refused(first[0]) and not refused(second[0]) and target.starts == 2
    finally:
        target.cleanup()
    assert refused(second[0])


def test_a_warm_spare_is_the_next_instance(tmp_path: Path) -> None:
    target = launch.Launcher(tiny(tmp_path), "127.0.0.1", 0, 0)
    target.spares = True
    try:
        target.start()
        spare = target._spare
        assert spare is not None and spare.pid is not None
        target.start()
        assert target.pid == spare.pid  # adopted, not started anew
        assert target._spare is not None and target._spare.pid is not None
        next_spare = target._spare.pid
        target.no_spares()
        assert gone(next_spare) and target.alive()  # the new spare is stopped, the adopted one runs on
    finally:
        target.cleanup()


def test_stop_ends_the_whole_process_group(tmp_path: Path) -> None:
    with launch.zoo("faithful", upstream="reference") as member:
        server = next(line for line in member.output if "behind at" in line)
        pid = int(server.rsplit("pid ", 1)[1].rstrip(")"))
        a = member.ports[0]
    assert gone(pid), "the reference server behind the member outlived it"
    assert refused(a)


def test_a_target_dies_with_the_harness_that_started_it(tmp_path: Path) -> None:
    harness = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys,time\nfrom pltf.harness import launch\n"
            "t = launch.Launcher(sys.argv[1], '127.0.0.1', 0, 0); t.start()\n"
            "print(t.pid, t.tmpdir, t._log.name, flush=True); time.sleep(60)",
            tiny(tmp_path),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert harness.stdout is not None
    pid, tmpdir, log = harness.stdout.readline().split()
    harness.send_signal(signal.SIGKILL)  # no clean-up runs in the harness
    harness.wait(5)
    harness.stdout.close()
    assert gone(int(pid)), "the target outlived a harness killed with SIGKILL"
    shutil.rmtree(tmpdir, ignore_errors=True)  # what the harness would have removed
    Path(log).unlink(missing_ok=True)


def test_a_target_that_fails_to_start_is_one_clear_error(tmp_path: Path) -> None:
    with pytest.raises(launch.LaunchError, match=r"exited.*unrecognized arguments"):
        launch.Launcher(f"{sys.executable} -m pltf.reference_server --no-such-option", "127.0.0.1", 0, 0).start()
    silent = launch.Launcher(f"{sys.executable} -c 'import time; time.sleep(30)'", "127.0.0.1", 0, 0)
    silent.start_timeout = 1.0
    with pytest.raises(launch.LaunchError, match="did not report two ports within 1 s"):
        silent.start()
    with pytest.raises(launch.LaunchError, match="cannot start"):
        launch.Launcher("/no/such/binary {ports}", "127.0.0.1", 0, 0).start()
    with pytest.raises(launch.LaunchError, match="unknown target kind"):
        launch.target("nonsense")


def test_the_emulator_is_started_like_the_reference_server() -> None:
    emulator_or_skip()
    with launch.emulator(time_scale=10.0) as emu:
        assert not refused(emu.ports[0]) and not refused(emu.ports[1])
        assert (emu.data() / "Map" / "PltfMap.map").is_file()  # the disk the reference server starts with
