"""``make demo``: start the reference server, run the conformance suite's standard tier against it, show the report.

The server runs as a real subprocess on ephemeral loopback ports with a throw-away data directory, at time
scale 10; the suite talks to it over TCP exactly as it would to a platform. Exit status is the suite's.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from pltf.cli.main import main as pltf

PORT_LINE = re.compile(r"server started at port (\d+)")
REPORT = Path("demo-report.html")


def start_server(data_dir: str, time_scale: float) -> tuple[subprocess.Popen[bytes], list[int], Path]:
    """Start the server with its log in a file (a pipe nobody drains would block it once full)."""
    log = Path(data_dir) / "server.log"
    cmd = [
        sys.executable,
        "-m",
        "pltf.reference_server",
        "--ports",
        "0,0",
        "--data-dir",
        str(Path(data_dir) / "disk"),
        "--time-scale",
        str(time_scale),
        "--seed",
        "1",
    ]
    with log.open("wb") as sink:
        proc = subprocess.Popen(cmd, stdout=sink, stderr=subprocess.STDOUT)
    deadline = time.monotonic() + 30
    ports: list[int] = []
    while len(ports) < 2 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.1)
        ports = [int(p) for p in PORT_LINE.findall(log.read_text(errors="replace"))]
    for line in log.read_text(errors="replace").splitlines():
        print(f"  server | {line}")
    if len(ports) < 2:
        proc.kill()
        raise SystemExit("demo: the reference server did not start")
    return proc, ports, log


def main() -> int:
    time_scale = 10.0
    with tempfile.TemporaryDirectory(prefix="pltf-demo-") as data_dir:
        print(f"Starting the reference server (data dir {data_dir}, time scale {time_scale:g}) ...")
        proc, (port_a, port_b), log = start_server(data_dir, time_scale)
        try:
            print(f"\nRunning the conformance suite (standard tier) against 127.0.0.1:{port_a} / {port_b} ...\n")
            status = pltf(
                [
                    "conform",
                    "--target",
                    f"127.0.0.1:{port_a}",
                    "--second-port",
                    str(port_b),
                    "--time-scale",
                    str(time_scale),
                    "--tier",
                    "standard",
                    "--allow-motion",
                    "--html",
                    str(REPORT),
                    "--json",
                    "demo-report.json",
                ]
            )
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
            print(f"\nServer log: {sum(1 for _ in log.open(errors='replace'))} lines, last ones:")
            for line in log.read_text(errors="replace").splitlines()[-5:]:
                print(f"  server | {line}")
    print(f"\nReport: {REPORT.resolve()} (open it in a browser); JSON: demo-report.json")
    # issue 19: the GUI on a reference server (the demo's own server was busy with the suite on both its ports)
    print(
        "\nTo watch and drive a reference server in the browser (PlatformCtrlGUI, guide ch. 5):\n"
        "  .venv/bin/pltf serve --ports 10000,10002 &\n"
        "  .venv/bin/pltf gui --target 127.0.0.1:10000 --open   # http://127.0.0.1:8080/?target=127.0.0.1:10000"
    )
    return status


if __name__ == "__main__":
    sys.exit(main())
