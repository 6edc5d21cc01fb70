"""``import pltf.client`` loads the client and the codec only (issue 18: under 100 ms).

The time itself is measured in benchmarks/bench_cli.py; here, deterministically, what it must not pay for:
jsonschema (the spec is schema-checked in CI, pltf.spec.check), asyncio (only AsyncPlatformClient needs it,
imported on first use), PyYAML (the spec is read from its JSON copies), nor anything of the toolkit.
"""

from __future__ import annotations

import json
import subprocess
import sys

NOT_FOR_THE_CLIENT = {
    "jsonschema",
    "asyncio",
    "yaml",
    "numpy",
    "scipy",
    "pymunk",
    "cantools",
    "lxml",
    "xmlschema",
    "rich",
    "can",
    "hypothesis",
    "pltf.reference_server",
    "pltf.conformance_tests",
    "pltf.fuzz",
    "pltf.spec.parameters",
    "pltf.spec.documents",
    "pltf.spec.errata",
    "pltf.spec.check",
}


def _modules_after(code: str) -> set[str]:
    probe = f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True)
    return set(json.loads(done.stdout.splitlines()[-1]))


def _loaded(modules: set[str], names: set[str]) -> set[str]:
    return {n for n in names if n in modules or any(m.startswith(n + ".") for m in modules)}


def test_import_pltf_client_loads_neither_jsonschema_nor_asyncio_nor_the_toolkit() -> None:
    modules = _modules_after("import pltf.client")
    assert _loaded(modules, NOT_FOR_THE_CLIENT) == set()


def test_a_blocking_session_needs_none_of_them_either() -> None:
    code = (
        "from pltf.client import PlatformClient, Status, MotionMode\n"
        "from pltf.spec.codec import REQUESTS, encode, decode_frame\n"
        "decode_frame(encode(REQUESTS.CMD_SET_MODE(mode=MotionMode.MODE_MOTION_VEL)), 'request')"
    )
    assert _loaded(_modules_after(code), NOT_FOR_THE_CLIENT) == set()


def test_the_asyncio_client_is_there_on_first_use() -> None:
    modules = _modules_after("from pltf.client import AsyncPlatformClient\nassert AsyncPlatformClient.connect")
    assert "asyncio" in modules and "pltf.client.aio" in modules
    assert _loaded(modules, NOT_FOR_THE_CLIENT - {"asyncio"}) == set()
