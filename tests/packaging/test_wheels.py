"""The three distributions, built and installed as a user installs them: outside the checkout.

``python -m build`` makes a wheel and an sdist of pltf-spec, pltf-client and pltf-toolkit; each is installed
from the wheels alone into a fresh virtual environment, and every command runs from an empty folder:
``pltf serve`` (seeding the fixture office), ``conform``, ``fuzz``, ``stubs``, ``decode``, ``encode``,
``run-program``. The client distribution alone brings no numpy, scipy, pymunk, cantools, lxml or jsonschema. The
toolkit's wheel is built with a compiler that always fails (``CC=false``): the install succeeds without the C
extensions and every command runs on their numpy fallbacks.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import time
import zipfile
from collections.abc import Iterator
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SOURCES = {"pltf_spec": "spec", "pltf_client": "clients", "pltf_toolkit": "."}
# what a build never reads: a copy without it is what a fresh clone holds (and build/ left over from an earlier
# build would put deleted modules back into a wheel)
UNTRACKED = shutil.ignore_patterns(
    ".git",
    ".venv",
    "build",
    "dist",
    "*.egg-info",
    "__pycache__",
    "*.so",
    "node_modules",
    ".mypy_cache",
    ".ruff_cache",
    ".pytest_cache",
    ".hypothesis",
)
HEAVY = {"numpy", "scipy", "pymunk", "cantools", "lxml", "jsonschema"}
STARTED = re.compile(r"server started at port (\d+)")
UV = Path(sys.executable).with_name("uv")  # the dev extra's uv
# building three distributions and installing numpy, scipy and the rest into fresh environments takes minutes
pytestmark = pytest.mark.timeout(1800)


def _run(
    *cmd: str | Path, cwd: Path, timeout: float = 600, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(
        [str(c) for c in cmd], cwd=cwd, capture_output=True, text=True, timeout=timeout, check=False, env=env
    )
    assert done.returncode == 0, f"{cmd}: {done.stdout[-2000:]}{done.stderr[-2000:]}"
    return done


@pytest.fixture(scope="module")
def dist(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("dist")
    tree = tmp_path_factory.mktemp("src") / "pltf"
    shutil.copytree(REPO, tree, ignore=UNTRACKED)
    no_compiler = dict(os.environ, CC="false", LDSHARED="false")
    for source in SOURCES.values():
        _run(
            sys.executable,
            "-m",
            "build",
            "--no-isolation",
            "--sdist",
            "--wheel",
            "--outdir",
            out,
            tree / source,
            cwd=tree / source,
            env=no_compiler,
        )
    return out


def _venv(root: Path, dist: Path, requirement: str, *, uv: bool = False) -> Path:
    """A fresh virtual environment with ``requirement`` installed from the wheels in ``dist`` (dependencies from
    the package index): by pip, or by uv, which fetches the toolkit's thirty dependencies in parallel (pip took
    90-130 s for them here, uv 4 s; the client's environment keeps pip, so both installers are exercised)."""
    _run(sys.executable, "-m", "venv", root, cwd=root.parent)
    py = root / "bin" / "python"
    if uv:
        _run(UV, "pip", "install", "--quiet", "--python", py, "--find-links", dist, requirement, cwd=root.parent)
    else:
        _run(py, "-m", "pip", "install", "--quiet", "--find-links", dist, requirement, cwd=root.parent)
    return py


@pytest.fixture(scope="module")
def toolkit(dist: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _venv(tmp_path_factory.mktemp("toolkit-env") / "venv", dist, "pltf-toolkit", uv=True)


@pytest.fixture
def empty(tmp_path: Path) -> Path:
    folder = tmp_path / "empty"
    folder.mkdir()
    return folder


def test_build_gives_a_wheel_and_an_sdist_of_each_distribution(dist: Path) -> None:
    names = sorted(p.name for p in dist.iterdir())
    for stem in SOURCES:
        assert any(n.startswith(stem) and n.endswith(".whl") for n in names), names
        assert any(n.startswith(stem) and n.endswith(".tar.gz") for n in names), names


def test_wheels_install_nothing_but_the_pltf_namespace(dist: Path) -> None:
    for wheel in dist.glob("*.whl"):
        assert not [n for n in zipfile.ZipFile(wheel).namelist() if n.endswith(".so")]  # built with CC=false
        tops = {name.split("/")[0] for name in zipfile.ZipFile(wheel).namelist()}
        assert {t for t in tops if not t.endswith(".dist-info")} == {"pltf"}, (wheel.name, tops)
        assert not any(n == "pltf/__init__.py" for n in zipfile.ZipFile(wheel).namelist())  # PEP 420 namespace


def test_without_a_compiler_the_toolkit_installs_and_runs_the_python_fallbacks(toolkit: Path, empty: Path) -> None:
    probe = (
        "from pltf.reference_server.world import geometry, raycast; from pltf.proxy import network; "
        "print(geometry.HAVE_C, raycast.HAVE_C, network.HAVE_C)"
    )
    assert _run(toolkit, "-c", probe, cwd=empty).stdout.split() == ["False", "False", "False"]


def test_the_client_distribution_alone_is_small_and_typed(dist: Path, tmp_path: Path, empty: Path) -> None:
    py = _venv(tmp_path / "client-env", dist, "pltf-client")
    installed = {line.split("==")[0].lower() for line in _run(py, "-m", "pip", "freeze", cwd=empty).stdout.split()}
    assert not installed & HEAVY, installed
    probe = (
        "import sys, pltf.client as c; print(c.__version__, sorted(set(sys.modules) & {'numpy', 'scipy', "
        "'pymunk', 'cantools', 'lxml', 'jsonschema', 'asyncio', 'yaml'}))"
    )
    out = _run(py, "-c", probe, cwd=empty).stdout.split(maxsplit=1)
    assert out[1].strip() == "[]", out
    site = Path(
        _run(py, "-c", "import pltf.client, os; print(os.path.dirname(pltf.client.__file__))", cwd=empty).stdout.strip()
    )
    assert (site / "py.typed").exists()


def test_codec_commands_from_an_empty_folder(toolkit: Path, empty: Path) -> None:
    pltf = toolkit.parent / "pltf"
    assert _run(pltf, "--version", cwd=empty).stdout.startswith("pltf ")
    decoded = json.loads(_run(pltf, "decode", "ff01fe02000000050f00000003", cwd=empty).stdout)
    assert decoded["telegram"] == "CMD_SET_MODE" and decoded["fields"] == {"mode": 3}
    encoded = _run(pltf, "encode", "CMD_SET_MODE", '{"mode": 3}', cwd=empty).stdout.strip()
    assert encoded == "ff01fe02000000050f00000003"
    _run(pltf, "stubs", "--lang", "go", "--out", empty / "go-client", cwd=empty)
    assert (empty / "go-client" / "protocol.go").exists()


@pytest.fixture
def served(toolkit: Path, empty: Path, tmp_path: Path) -> Iterator[list[int]]:
    """``pltf serve`` from the wheel; its log goes to a file (a pipe nobody drains would fill up and stop it)."""
    log = tmp_path / "serve.log"
    with log.open("wb") as out:
        proc = subprocess.Popen(
            [
                toolkit.parent / "pltf",
                "serve",
                "--ports",
                "0,0",
                "--data-dir",
                "data",
                "--time-scale",
                "20",
                "--log-level",
                "INFO",
            ],
            cwd=empty,
            stdout=out,
            stderr=subprocess.STDOUT,
        )
    deadline = time.monotonic() + 60
    while len(ports := [int(p) for p in STARTED.findall(log.read_text(errors="replace"))]) < 2:
        if proc.poll() is not None or time.monotonic() > deadline:
            break
        time.sleep(0.05)
    try:
        assert len(ports) == 2, "pltf serve did not start:\n" + log.read_text(errors="replace")[-2000:]
        yield ports
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            raise AssertionError("pltf serve did not stop within 20 s of SIGTERM") from None


def test_serve_seeds_the_fixtures_and_the_tools_run_against_it(toolkit: Path, empty: Path, served: list[int]) -> None:
    pltf = toolkit.parent / "pltf"
    seeded = {p.name for p in (empty / "data").rglob("*") if p.is_file()}
    assert {"office.map", "office.rm"} <= seeded or any(n.endswith(".map") for n in seeded), seeded
    target = f"127.0.0.1:{served[0]}"
    fixtures = Path(_run(toolkit, "-c", "import pltf.fixtures as f; print(f.DIR)", cwd=empty).stdout.strip())
    (empty / "disk" / "Map").mkdir(parents=True)  # remote mode: <load> reads DIR/Map/NAME here, then sends it
    shutil.copy(fixtures / "maps" / "office.map", empty / "disk" / "Map" / "office.map")
    (empty / "mission.xml").write_text(
        "<?xml version='1.0' encoding='UTF-8'?><program version='1.0'>"
        "<task name='main' priority='0'><load map='office.map'/>"
        "<log message='map sent from the wheel'/></task></program>"
    )
    ran = _run(
        pltf,
        "run-program",
        "mission.xml",
        "--target",
        f"127.0.0.1:{served[1]}",
        "--data-dir",
        "disk",
        "--time-scale",
        "20",
        "--plain",
        cwd=empty,
    )
    assert "map sent from the wheel" in ran.stdout
    conform = subprocess.run(
        [
            pltf,
            "conform",
            "--target",
            target,
            "--second-port",
            str(served[1]),
            "--tier",
            "smoke",
            "--time-scale",
            "20",
            "--json",
            "report.json",
            "--stateful",
            "3",
        ],
        cwd=empty,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert conform.returncode == 0, conform.stdout[:6000] + conform.stderr[-2000:]
    assert json.loads((empty / "report.json").read_text())
    fuzz = subprocess.run(
        [
            pltf,
            "fuzz",
            "--target",
            target,
            "--second-port",
            str(served[1]),
            "--duration",
            "3",
            "--seed",
            "1",
            "--quiet",
            "--out",
            "findings",
        ],
        cwd=empty,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    # the command runs from the wheel; whether a 3 s campaign on a loaded machine judges right is tests/fuzz's
    assert fuzz.returncode in (0, 1), fuzz.stdout[-3000:] + fuzz.stderr[-2000:]
    assert json.loads((empty / "findings" / "summary.json").read_text())["cases"] > 0
