"""The known addresses (guide 5.2 Network.ini) and the gateway's command line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from pltf.gui.network_ini import NetworkIni

REPO = Path(__file__).resolve().parents[2]


def test_targets_are_read_added_once_and_bad_lines_skipped(tmp_path: Path) -> None:
    ini = NetworkIni(tmp_path / "sub" / "Network.ini")
    assert ini.targets() == []
    ini.add("127.0.0.1:10000")
    ini.add("127.0.0.1:10000")
    ini.add("lab:10002")
    assert ini.targets() == ["127.0.0.1:10000", "lab:10002"]
    ini.path.write_text(ini.path.read_text() + "broken = no-port\n")
    assert ini.targets() == ["127.0.0.1:10000", "lab:10002"]
    ini.path.write_text("not an ini file at all [")
    assert ini.targets() == []


def test_pltf_gui_refuses_a_bad_target_in_one_line() -> None:
    out = subprocess.run(
        [sys.executable, "-m", "pltf.cli.main", "gui", "--target", "nowhere"],
        capture_output=True,
        text=True,
        check=False,
        cwd=REPO,
        timeout=60,
    )
    assert out.returncode == 2
    assert out.stderr.strip() == (
        "pltf gui: error: argument --target: expected HOST:PORT with PORT 1..65535, got 'nowhere'"
    )
