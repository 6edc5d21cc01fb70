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

from pltf_cli.main import main as pltf

PORT_LINE = re.compile(r"server started at port (\d+)")
REPORT = Path("demo-report.html")


def start_server(data_dir: str, time_scale: float) -> tuple[subprocess.Popen[str], list[int]]:
    cmd = [sys.executable, "-m", "reference_server", "--ports", "0,0", "--data-dir", data_dir,
           "--time-scale", str(time_scale), "--seed", "1"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    ports: list[int] = []
    deadline = time.monotonic() + 30
    assert proc.stdout is not None
    while len(ports) < 2 and time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        print(f"  server | {line.rstrip()}")
        if m := PORT_LINE.search(line):
            ports.append(int(m.group(1)))
    if len(ports) < 2:
        proc.kill()
        raise SystemExit("demo: the reference server did not start")
    return proc, ports


def main() -> int:
    time_scale = 10.0
    with tempfile.TemporaryDirectory(prefix="pltf-demo-") as data_dir:
        print(f"Starting the reference server (data dir {data_dir}, time scale {time_scale:g}) ...")
        proc, (port_a, port_b) = start_server(data_dir, time_scale)
        try:
            print(f"\nRunning the conformance suite (standard tier) against 127.0.0.1:{port_a} / {port_b} ...\n")
            status = pltf([
                "conform", "--target", f"127.0.0.1:{port_a}", "--second-port", str(port_b),
                "--time-scale", str(time_scale), "--tier", "standard", "--allow-motion",
                "--html", str(REPORT), "--json", "demo-report.json",
            ])
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
    print(f"\nReport: {REPORT.resolve()} (open it in a browser); JSON: demo-report.json")
    return status


if __name__ == "__main__":
    sys.exit(main())
