"""The server as a process: command line, start-up log, exit status, signals, SIGKILL in the middle of SAVE_MAP."""

from __future__ import annotations

import os
import random
import signal
import socket
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from pltf.reference_server.storage import FILES, Storage
from pltf.spec.codec import REQUESTS, encode
from pltf.spec.documents import DocumentKind, validate_document
from tests.reference_server.conftest import Client, ServerProcess
from tests.reference_server.helpers import REPO, wait_for

R = REQUESTS


def test_start_up_log_and_exit_status_after_cmd_exit(tmp_path: Path) -> None:
    srv = ServerProcess(tmp_path / "data", tmp_path / "log")
    try:
        with Client(srv.ports[0]) as c:
            assert c.status().operation_state == 3  # ST_OP_NOT_INITIALIZED
            c.send(R.CMD_EXIT())
            assert c.closed_by_server()
        assert srv.wait() == 0
    finally:
        srv.kill()
    log = srv.log()
    for line in (
        "server started at port",
        "init pose read from",
        "load map: ",
        "load roadmap: ",
        "system state: ",
        "server stopped",
    ):
        assert line in log, line
    assert len(set(srv.ports)) == 2 and 0 not in srv.ports


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=lambda s: s.name)
def test_signals_exit_cleanly(tmp_path: Path, sig: signal.Signals) -> None:
    srv = ServerProcess(tmp_path / "data", tmp_path / "log")
    try:
        with Client(srv.ports[1]) as c:
            c.status()
            srv.proc.send_signal(sig)
            assert c.closed_by_server()
        assert srv.wait() == 0
    finally:
        srv.kill()
    assert f"{sig.name} received" in srv.log()


def test_pltf_serve_is_the_same_server(tmp_path: Path) -> None:
    srv = ServerProcess(
        tmp_path / "data", tmp_path / "log", "--seed", "7", "--log-level", "DEBUG", module="pltf.cli.main"
    )
    try:
        with Client(srv.ports[0]) as c:
            assert c.request(R.CMD_GET_MAP()).name == "PltfMap.map"
            c.send(R.CMD_EXIT())
        assert srv.wait() == 0
    finally:
        srv.kill()


@pytest.mark.parametrize("args", [["--ports", "10000,x"], ["--ports", "70000"], ["--time-scale", "0"]])
def test_bad_options_exit_2(args: list[str]) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "pltf.reference_server", *args], cwd=REPO, capture_output=True, timeout=20, check=False
    )
    assert done.returncode == 2
    assert b"error" in done.stderr


def test_a_port_in_use_is_a_one_line_error(tmp_path: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = subprocess.run(
            [sys.executable, "-m", "pltf.reference_server", "--ports", f"0,{port}", "--data-dir", str(tmp_path)],
            cwd=REPO,
            capture_output=True,
            timeout=20,
            check=False,
        )
    assert done.returncode == 2
    assert b"cannot listen" in done.stderr


# ---- SIGKILL in the middle of SAVE_MAP
RUNS = 30
SAVES_PER_SET = 10


def _big_map(tag: int, lines: int = 3000) -> bytes:
    body = "".join(f'<line><point x="{i}" y="{tag}"/><point x="{i}" y="{tag + 1000}"/></line>\n' for i in range(lines))
    return f'<?xml version="1.0"?>\n<map Version="1.0"><layer index="{tag}">\n{body}</layer></map>\n'.encode()


def _kill_during_saves(root: Path, seed: int, docs: tuple[bytes, bytes]) -> tuple[bytes, bool]:
    """Start a server, stream SET_MAP/SAVE_MAP, SIGKILL it at a random instant; the map file and whether a
    temporary file of an unfinished save was found."""
    rng = random.Random(seed)
    srv = ServerProcess(root / "data", root / "log", "--motion", "ideal")  # storage, not the world, is tested
    batch = b"".join(
        encode(R.CMD_SET_MAP(name=f"m{k}", xml=doc.decode("latin-1"))) + encode(R.CMD_SAVE_MAP()) * SAVES_PER_SET
        for k, doc in enumerate(docs)
    )
    client = Client(srv.ports[0])

    def stream() -> None:
        try:
            while True:
                client.send_raw(batch)
        except OSError:
            pass  # the server died

    sender = threading.Thread(target=stream, daemon=True)
    try:
        sender.start()
        map_file = root / "data" / FILES[DocumentKind.MAP]
        original = map_file.read_bytes()
        wait_for(lambda: map_file.read_bytes() != original, timeout=10)  # the first save went through
        time.sleep(rng.uniform(0.0, 0.15))
        srv.proc.send_signal(signal.SIGKILL)
        assert srv.wait() == -signal.SIGKILL
    finally:
        srv.kill()
        client.close()
        sender.join(5)
    temporaries = [p for p in map_file.parent.iterdir() if p.name != map_file.name]
    return map_file.read_bytes(), bool(temporaries)


def test_sigkill_during_save_map_leaves_the_old_or_the_new_file(tmp_path: Path) -> None:
    docs = (_big_map(1), _big_map(2))
    old = (REPO / "fixtures" / "maps" / "office.map").read_bytes()
    with ThreadPoolExecutor(max_workers=min(4, os.cpu_count() or 1)) as pool:
        results = list(pool.map(lambda i: _kill_during_saves(tmp_path / f"run{i}", i, docs), range(RUNS)))
    for i, (content, _) in enumerate(results):
        assert content in (old, *docs), f"run {i}: torn map file of {len(content)} bytes"
        validate_document(DocumentKind.MAP, content)
    # evidence that kills landed inside a save (a temporary file was being written), not only between saves
    assert sum(torn_write for _, torn_write in results) >= 1
    # re-opening the data dir removes the temporaries, and the map loads
    for i in range(RUNS):
        store = Storage(tmp_path / f"run{i}" / "data")
        assert [p.name for p in store.path(DocumentKind.MAP).parent.iterdir()] == ["PltfMap.map"]
