"""The tested blocks of a documentation page, and a runner that runs them as a reader would.

A fenced block is tested when the line right above it is a marker comment (invisible on the site):

    <!-- doc-test -->                               run it (bash); it must exit 0
    <!-- doc-test exit=1 expect="findings" -->      it must exit 1 and print "findings" (stdout or stderr)
    <!-- doc-test background until="server started at port" count=2 -->
                                                    start it, wait until its output has the text twice;
                                                    it runs until the page's last block is done
    <!-- doc-test file=hello.py -->                 write the block into hello.py (for the blocks after it)
    <!-- doc-test slow ... -->                      only in the slow tier (make test-slow)

Rules: the blocks of a page run in order in one fresh folder, with the venv's `pltf` and `python` first on PATH
and `examples`, `fixtures` linked from the repository (a reader runs them from the checkout's root). The
well-known ports a page names (10000/10002 the platform, 10010/10012 a proxy, 8080 the GUI) become free ports
of this machine in the shell blocks (a file block is written as it is), so pages run beside each other and
beside other tests; nothing leaves 127.0.0.1.
"""

from __future__ import annotations

import os
import re
import shlex
import signal
import socket
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
VENV_BIN = REPO / ".venv" / "bin"
MARKER = re.compile(r"^<!--\s*doc-test\b(.*?)-->\s*$")
FENCE = re.compile(r"^(```+|~~~+)\s*([\w+-]*)")
OPTION = re.compile(r'(\w+)(?:=("[^"]*"|\S+))?')
# a port of the pages -> its offset in the block of ports the runner takes (pairs stay PORT, PORT+2: guide 6.1)
PORTS = {10000: 0, 10002: 2, 10010: 4, 10012: 6, 8080: 8}
BLOCK_TIMEOUT = 180.0
SLOW_TIMEOUT = 600.0


@dataclass(frozen=True)
class Block:
    page: str
    line: int  # of the fence, 1-based
    lang: str
    code: str
    exit: int = 0
    expect: str = ""
    background: bool = False
    until: str = ""
    count: int = 1
    file: str = ""
    slow: bool = False

    def where(self) -> str:
        return f"{self.page}:{self.line}"


def _options(text: str) -> dict[str, str]:
    return {m.group(1): (m.group(2) or "").strip('"') for m in OPTION.finditer(text)}


def parse(text: str, page: str) -> list[Block]:
    """The tested blocks of a page, in order. ValueError for a marker with no block under it or an unknown key."""
    lines = text.splitlines()
    blocks = []
    for i, line in enumerate(lines):
        marker = MARKER.match(line)
        if not marker:
            continue
        fence = FENCE.match(lines[i + 1]) if i + 1 < len(lines) else None
        if not fence:
            raise ValueError(f"{page}:{i + 1}: a doc-test marker must be right above a fenced block")
        end = next((j for j in range(i + 2, len(lines)) if lines[j].startswith(fence.group(1))), None)
        if end is None:
            raise ValueError(f"{page}:{i + 2}: the fenced block is not closed")
        opts = _options(marker.group(1))
        unknown = set(opts) - {"exit", "expect", "background", "until", "count", "file", "slow"}
        if unknown:
            raise ValueError(f"{page}:{i + 1}: unknown doc-test option {sorted(unknown)}")
        blocks.append(
            Block(
                page=page,
                line=i + 2,
                lang=fence.group(2),
                code="\n".join(lines[i + 2 : end]) + "\n",
                exit=int(opts.get("exit", "0")),
                expect=opts.get("expect", ""),
                background="background" in opts,
                until=opts.get("until", ""),
                count=int(opts.get("count", "1")),
                file=opts.get("file", ""),
                slow="slow" in opts,
            )
        )
    return blocks


def free_ports() -> dict[int, int]:
    """The page's well-known ports -> a base B with B, B+2, ..., B+8 free on 127.0.0.1 (checked by binding)."""
    for _ in range(200):
        with socket.socket() as probe:
            probe.bind(("127.0.0.1", 0))
            base = probe.getsockname()[1]
        if base + max(PORTS.values()) > 65535:
            continue
        if all(_free(base + off) for off in PORTS.values()):
            return {port: base + off for port, off in PORTS.items()}
    raise RuntimeError("no block of free ports on 127.0.0.1")


def _free(port: int) -> bool:
    with socket.socket() as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def localize(code: str, ports: dict[int, int]) -> str:
    return re.sub(r"\b(10000|10002|10010|10012|8080)\b", lambda m: str(ports[int(m.group(1))]), code)


class PageRun:
    """Runs one page's blocks in a fresh folder; ``close`` stops what its background blocks started."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.ports = free_ports()
        self.env = dict(os.environ, PATH=f"{VENV_BIN}{os.pathsep}{os.environ.get('PATH', '')}")
        self.env.pop("PLTF_TRACEBACK", None)
        self.background: list[tuple[subprocess.Popen[bytes], Path]] = []
        for name in ("examples", "fixtures"):
            (folder / name).symlink_to(REPO / name)

    def run(self, block: Block) -> str:
        """Run ``block``; its output. AssertionError naming the block when it does not do what the page says."""
        if block.file:  # verbatim: a program's numbers are not ports (y_mm=10000); it takes its target as an argument
            (self.folder / block.file).write_text(block.code, encoding="utf-8")
            return ""
        code = localize(block.code, self.ports)
        if block.background:
            return self._start(block, code)
        timeout = SLOW_TIMEOUT if block.slow else BLOCK_TIMEOUT
        proc = subprocess.run(
            ["bash", "-e", "-o", "pipefail", "-c", code],
            cwd=self.folder,
            env=self.env,
            capture_output=True,
            timeout=timeout,
            check=False,
        )
        out = (proc.stdout + proc.stderr).decode(errors="replace")
        assert proc.returncode == block.exit, (
            f"{block.where()}: exit status {proc.returncode}, the page says {block.exit}:\n{code}\n{out[-3000:]}"
        )
        assert block.expect in out, f"{block.where()}: the output lacks {block.expect!r}:\n{code}\n{out[-3000:]}"
        return out

    def _start(self, block: Block, code: str) -> str:
        log = self.folder / f"background-{block.line}.log"
        with log.open("wb") as sink:
            proc = subprocess.Popen(
                ["bash", "-c", f"exec {code.strip()}" if "\n" not in code.strip() else code],
                cwd=self.folder,
                env=self.env,
                stdout=sink,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        self.background.append((proc, log))
        deadline = time.monotonic() + BLOCK_TIMEOUT
        while time.monotonic() < deadline:
            out = log.read_text(errors="replace")
            if out.count(block.until) >= block.count:
                return out
            assert proc.poll() is None, f"{block.where()}: ended with status {proc.returncode}:\n{code}\n{out[-3000:]}"
            time.sleep(0.05)
        raise AssertionError(f"{block.where()}: no {block.until!r} x{block.count} within {BLOCK_TIMEOUT} s:\n{code}")

    def close(self) -> None:
        for proc, _ in reversed(self.background):
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGTERM)  # the group this runner started for the block, by its id
                try:
                    proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    os.killpg(proc.pid, signal.SIGKILL)
                    proc.wait()


def describe(block: Block) -> str:
    return f"{block.where()} {shlex.quote(block.code.splitlines()[0] if block.code.strip() else '')}"
