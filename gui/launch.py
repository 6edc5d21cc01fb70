"""Start ``pltf gui`` as a child process on an ephemeral port: the one start-up of the browser tests
(tests/gui/conftest.py) and the benchmarks (benchmarks/bench_gui.py).

Rules:
- The process is a ``pltf.harness.launch.Launched``: its own session, ended with whatever it started, SIGTERM when
  its harness dies, and its stdout and stderr in a log FILE. Never a pipe: the gateway logs a line per connection
  event, and a pipe nobody reads fills at 64 KB; the next log call then blocks the gateway's one thread and every
  viewer with it (the stall of the whole tests/gui run, session gui19b; tests/gui/test_gateway.py).
- Ready when the log says ``gui serving at http://HOST:PORT/``; ``base`` is that ``http://HOST:PORT`` and
  ``token`` the printed URL's token (None without one).
- The tests' and benchmarks' platforms listen on ephemeral ports, so the gateway is started with
  ``--allow-any-target`` unless asked otherwise (``allow_any_target=False``; tests/gui/test_doors*.py check the
  list of targets); ``args`` are further options of ``pltf gui``.
"""

from __future__ import annotations

import re
import time
from pathlib import Path
from urllib.parse import parse_qs, urlsplit

from pltf.harness.launch import REPO, Launched, LaunchError, python

SERVING = re.compile(r"gui serving at (http://[^/\s]+)/(\S*)")


class GatewayProcess(Launched):
    """``pltf gui`` listening on a free port of 127.0.0.1."""

    def __init__(
        self,
        ini: Path,
        *,
        target: str | None = "127.0.0.1:1",
        reply_timeout: float | None = None,
        start_timeout: float = 30.0,
        listen: str = "127.0.0.1:0",
        allow_any_target: bool = True,
        args: tuple[str, ...] = (),
    ) -> None:
        argv = python("pltf.cli.main", "gui", "--listen", listen, "--network-ini", str(ini))
        argv += ["--target", target] if target is not None else []  # None: `args` name the platforms (--fleet)
        if reply_timeout is not None:
            argv += ["--reply-timeout", f"{reply_timeout:g}"]
        if allow_any_target:
            argv.append("--allow-any-target")
        super().__init__([*argv, *args], name="pltf gui", start_timeout=start_timeout)
        self.ini = ini
        self.base = ""
        self.token: str | None = None

    def _ready(self) -> tuple[int, int]:
        self.starts += 1
        deadline = time.monotonic() + self.start_timeout
        while self.alive() and time.monotonic() < deadline and not SERVING.search(self._read_log()):
            time.sleep(0.02)
        found = SERVING.search(self._read_log())
        if found is None:
            why = "exited" if not self.alive() else f"did not serve within {self.start_timeout:g} s"
            self.stop()
            hint = "" if (REPO / "gui" / "static" / "index.html").is_file() else " (the GUI is not built: `make gui`)"
            raise LaunchError(f"pltf gui {why}{hint}: {' | '.join(self.output[-8:])}")
        self.base = found.group(1)
        self.token = parse_qs(urlsplit(found.group(2)).query).get("token", [None])[0]
        return self.ports

    def url(self, target: str) -> str:
        return f"{self.base}/?target={target}" + (f"&token={self.token}" if self.token else "")

    def log_size(self) -> int:
        """Bytes the gateway has written to its log so far."""
        return Path(self._log.name).stat().st_size if self._log is not None else 0
