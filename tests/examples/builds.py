"""Builds of the TypeScript and C++ examples against the committed generated clients, cached by their content.

An example's folder (examples/typescript, examples/cpp) is copied with its ``build.sh`` into a cache directory
named after a hash of everything the build reads (the example's files, the generated client, the build script),
built there once (``PLATFORMCTRL`` points the script at the generated client) and reused until one of those files
changes: a C++ or TypeScript build takes 20-60 s on a loaded machine, a test run against a cached one none. The
cache is ``$PLTF_EXAMPLES_CACHE`` or ``~/.cache/pltf-examples``; a missing toolchain skips the test and says so.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.examples.runner import EXAMPLES, REPO

TOOLS = {"typescript": ("node", "npm"), "cpp": ("g++",)}
SKIP_DIRS = {"node_modules", "dist", "build", "platformctrl"}
BUILD_TIMEOUT = 600


@dataclass(frozen=True)
class Build:
    kind: str
    out: Path

    def command(self, name: str) -> list[str]:
        """How to run the built example ``name`` (patrol)."""
        if self.kind == "typescript":
            return ["node", str(self.out / "dist" / f"{name}.js")]
        return [str(self.out / "build" / name)]


def _files(root: Path) -> list[Path]:
    return sorted(p for p in root.rglob("*") if p.is_file() and not SKIP_DIRS & set(p.relative_to(root).parts[:-1]))


def _key(kind: str) -> str:
    digest = hashlib.sha256()
    for root in (EXAMPLES / kind, REPO / "clients" / "generated" / kind):
        for path in _files(root):
            digest.update(str(path.relative_to(REPO)).encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def cache_dir() -> Path:
    return Path(os.environ.get("PLTF_EXAMPLES_CACHE") or Path.home() / ".cache" / "pltf-examples")


@functools.cache
def build(kind: str) -> Build:
    """The example folder ``kind`` built (once per content, see the module's doc)."""
    missing = [tool for tool in TOOLS[kind] if shutil.which(tool) is None]
    if missing:
        pytest.skip(f"TOOLCHAIN MISSING for {kind}: {', '.join(missing)} not on PATH")
    out = cache_dir() / f"{kind}-{_key(kind)}"
    if (out / ".built").exists():
        return Build(kind, out)
    work = out.with_name(f"{out.name}.tmp{os.getpid()}")
    shutil.rmtree(work, ignore_errors=True)
    shutil.copytree(EXAMPLES / kind, work, ignore=shutil.ignore_patterns(*SKIP_DIRS))
    env = {
        **os.environ,
        "PLATFORMCTRL": str(REPO / "clients" / "generated" / kind),
        "npm_config_update_notifier": "false",
        "npm_config_fund": "false",
        "npm_config_audit": "false",
    }
    proc = subprocess.run(
        ["sh", "build.sh"], cwd=work, env=env, capture_output=True, text=True, timeout=BUILD_TIMEOUT, check=False
    )
    if proc.returncode != 0:
        tail = "\n".join((proc.stdout + proc.stderr).splitlines()[-30:])
        raise AssertionError(f"examples/{kind}: sh build.sh failed ({proc.returncode}):\n{tail}")
    (work / ".built").touch()
    try:
        work.rename(out)
    except OSError:  # another run built the same content meanwhile
        shutil.rmtree(work, ignore_errors=True)
    return Build(kind, out)
