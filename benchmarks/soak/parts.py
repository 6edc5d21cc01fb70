"""The soak's parts, each a process of its own: the reference server, ``pltf proxy --record`` in front of it, the
GUI gateway with the GUI open in Debian's chromium, the patrol example and the reconnecting client.

Rules:
- Every client reaches the server through the proxy, so the recording holds all that happened. Guide 6.1: one
  client per port. The GUI holds the first port, the patrol the second; the reconnecting client connects to the
  second port too, so the server turns it away (FIN) every few seconds while the patrol drives: a connection's
  whole life (accept, forward, record, turn away, close) in every process, every few seconds.
- Each part is a ``pltf.harness.launch.Launched``: its own session, a log FILE (never a pipe), SIGTERM when the
  harness dies. The browser is the harness's own child (Playwright); ``Parts.processes`` names every pid.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmarks.soak.procs import cmdline, comm, descendants
from pltf.gui.launch import GatewayProcess
from pltf.harness.launch import REPO, Launched, LaunchError, python, reference

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking"]
LISTENING = re.compile(r"proxy listening at [^:\s]+:(\d+)")
CHILDREN = {"pltf proxy": "recorder"}  # what a part's child process is (proxy/offload.py forks the recorder)
PAGE_TIMEOUT_MS = 120_000  # a loaded 2-core machine (load 20-40) took over 30 s to show the GUI connected
PROXY_STOP_GRACE = 300.0  # s: the proxy's exit waits until its recorder has written everything


class Plain(Launched):
    """A child that is ready as soon as it runs (a client)."""

    def whole_output(self) -> list[str]:
        """Every line it wrote so far (``output`` keeps only the last 200)."""
        return self._read_log(1 << 30).splitlines()

    def _ready(self) -> tuple[int, int]:
        self.starts += 1
        time.sleep(0.2)
        if not self.alive():
            raise LaunchError(f"{self.name} exited at once: {' | '.join(self.output[-8:])}")
        return self.ports


class ProxyProcess(Launched):
    """``pltf proxy --record`` on two free ports in front of ``ports`` of 127.0.0.1; ready when it listens."""

    def __init__(self, ports: tuple[int, int], record: Path) -> None:
        argv = python(
            "pltf.cli.main", "proxy", "--listen", "127.0.0.1:0", "--target", f"127.0.0.1:{ports[0]}",
            "--second", f"0:{ports[1]}", "--record", str(record), "--quiet",
        )  # fmt: skip
        super().__init__(argv, name="pltf proxy")

    def _ready(self) -> tuple[int, int]:
        self.starts += 1
        deadline = time.monotonic() + self.start_timeout
        while self.alive() and time.monotonic() < deadline and len(LISTENING.findall(self._read_log())) < 2:
            time.sleep(0.05)
        seen = [int(p) for p in LISTENING.findall(self._read_log())]
        if len(seen) < 2:
            self.stop()
            raise LaunchError(f"pltf proxy did not listen on two ports: {' | '.join(self.output[-8:])}")
        self.ports = (seen[0], seen[1])
        return self.ports

    def stop_gently(self, grace: float = PROXY_STOP_GRACE) -> int | None:
        """SIGINT to the proxy alone (what Ctrl-C does to it) and time to write the recording's tail, then ``stop``.
        (SIGTERM to its whole process group ends its recorder process at once as well: the tail is lost.)"""
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.proc.wait(grace)
        code = self.exit_code()
        self.stop()
        return code


@dataclass
class Parts:
    server: Launched
    proxy: ProxyProcess
    gateway: GatewayProcess
    patrol: Plain
    reconnect: Plain
    page: Any = None
    record: Path = field(default_factory=Path)

    def launched(self) -> dict[str, Launched]:
        return {
            "reference server": self.server,
            "pltf proxy": self.proxy,
            "GUI gateway": self.gateway,
            "patrol": self.patrol,
            "reconnecting client": self.reconnect,
        }

    def processes(self) -> dict[int, str]:
        """Every process of the soak by pid, named: a part's own process, what it started (the proxy's recorder),
        and the browser's processes (chromium's by their --type, Playwright's driver)."""
        out: dict[int, str] = {}
        for name, part in self.launched().items():
            if part.pid is not None:
                out[part.pid] = name
                for child in descendants(part.pid):
                    out[child] = f"{name}: {CHILDREN.get(name, comm(child))}"
        for pid in descendants(os.getpid()):
            if pid not in out:
                out[pid] = _browser_name(pid)
        return out

    def dead(self) -> list[str]:
        return [f"{name} (exit status {p.exit_code()})" for name, p in self.launched().items() if not p.alive()]


def _browser_name(pid: int) -> str:
    """``chromium renderer``, ``chromium utility (network.mojom.NetworkService)``, ...; chromium rewrites its
    command line as one string, so the options are split on spaces."""
    args = [a for arg in cmdline(pid) for a in arg.split(" ")]
    option = {k: v for k, _, v in (a.partition("=") for a in args if a.startswith("--"))}
    name = comm(pid)
    if name.startswith("chrom"):
        sub = option.get("--utility-sub-type")
        return f"chromium {option.get('--type', 'browser')}" + (f" ({sub})" if sub else "")
    return "Playwright driver" if name.startswith("node") else name


@contextlib.contextmanager
def started(workdir: Path, time_scale: float, reconnect_every: float) -> Iterator[Parts]:
    """Every part up, in order, the GUI open and connected; everything stopped at the end (the proxy last, with
    time to write its recording)."""
    record = workdir / "session.jsonl"
    server = reference(time_scale=time_scale, seed=1)
    with contextlib.ExitStack() as stack:
        stack.callback(server.cleanup)
        p1, p2 = server.start()
        proxy = ProxyProcess((p1, p2), record)
        stack.callback(proxy.cleanup)
        stack.callback(proxy.stop_gently)
        l1, l2 = proxy.start()
        gateway = GatewayProcess(workdir / "Network.ini", target=f"127.0.0.1:{l1}")
        stack.callback(gateway.cleanup)
        gateway.start()
        page = stack.enter_context(_browser(gateway.url(f"127.0.0.1:{l1}")))
        patrol = Plain([sys.executable, str(REPO / "examples" / "patrol.py"), "--target", f"127.0.0.1:{l2}",
                        "--rounds", "0"], name="patrol")  # fmt: skip
        stack.callback(patrol.cleanup)
        patrol.start()
        time.sleep(1.0)  # the patrol holds the second port before the first newcomer comes
        reconnect = Plain(
            python("benchmarks.soak.reconnect", "--target", f"127.0.0.1:{l2}", "--every", f"{reconnect_every:g}"),
            name="reconnecting client",
        )
        stack.callback(reconnect.cleanup)
        reconnect.start()
        yield Parts(server, proxy, gateway, patrol, reconnect, page, record)


@contextlib.contextmanager
def _browser(url: str) -> Iterator[Any]:
    from playwright.sync_api import Error as PlaywrightError
    from playwright.sync_api import expect, sync_playwright

    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 900})
            try:
                page.goto(url, timeout=PAGE_TIMEOUT_MS)
                expect(page.get_by_role("status", name="Connection")).to_contain_text(
                    "connected", timeout=PAGE_TIMEOUT_MS
                )
            except (AssertionError, PlaywrightError) as exc:
                first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                raise LaunchError(f"the GUI at {url} did not show 'connected' in chromium: {first}") from None
            yield page
        finally:
            browser.close()
