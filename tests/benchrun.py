"""The smoke tests of the benchmarks run ``python -m benchmarks --quick --only NAME`` as a user would and read the
JSON report it writes (no figure is asserted: --quick figures mean nothing)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def quick(only: str, out: Path, timeout: float) -> dict[str, Any]:
    """Run the benchmarks named ``only`` at --quick, writing ``out``; the report, after asserting exit status 0."""
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks", "--quick", "--only", only, "--json", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    report: dict[str, Any] = json.loads(out.read_text())
    return report
