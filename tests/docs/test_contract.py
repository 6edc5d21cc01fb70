"""The import contract (``[tool.importlinter]`` in pyproject.toml; make test runs lint-imports on it) is not
vacuous: without its listed exceptions the same layers are broken exactly where the exceptions say.
"""

from __future__ import annotations

import json
import subprocess
import tomllib
from pathlib import Path

from tests.docs.blocks import REPO, VENV_BIN


def _lint(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(VENV_BIN / "lint-imports"), "--no-cache", *args],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )


def test_without_its_exceptions_the_layers_are_broken_where_they_say(tmp_path: Path) -> None:
    config = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["importlinter"]
    layers = next(c for c in config["contracts"] if c["id"] == "layers")
    bare = tmp_path / "contract.toml"
    bare.write_text(
        "[tool.importlinter]\n"
        f"root_packages = {json.dumps(config['root_packages'])}\n"
        "[[tool.importlinter.contracts]]\n"
        'id = "layers"\nname = "layers"\ntype = "layers"\n'
        f"layers = {json.dumps(layers['layers'])}\n",
        encoding="utf-8",
    )
    proc = _lint("--config", str(bare))
    assert proc.returncode == 1, proc.stdout[-3000:]
    report = " ".join(proc.stdout.split())
    for rule in ("pltf.gui.recorded -> pltf.proxy.session", "pltf.conformance_tests.fleet -> pltf.cli.options"):
        assert f"- {rule}" in report, rule
