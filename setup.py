"""Where the toolkit's folders go in the ``pltf`` import namespace, and its optional C extensions.

Everything else about the distribution is in pyproject.toml. The folders stay at the top of the repository
(the layout is part of the product); each is installed as one subpackage of the namespace ``pltf`` (PEP 420:
there is no ``pltf/__init__.py``, so the client and spec distributions add theirs beside it).

The C extensions (inner loops of the ray caster and the planner's segment tests, the proxy's forwarding loop, the
fuzzer's drawing core) are optional: without a compiler, or when ``PLTF_NO_EXTENSIONS=1``, the build goes on and
the numpy fallbacks of reference_server/world/raycast.py and geometry.py run, the proxy forwards with Python
threads and the fuzzer draws its cases in Python.
-ffp-contract=off: no fused multiply-add, so the C loops round every product as numpy does (the tests hold them
to numpy bit for bit).
"""

from __future__ import annotations

import os
import sys

from setuptools import Extension, find_packages, setup
from setuptools.command.build_ext import build_ext

# import name -> folder. spec/ and clients/pltf_client/ are distributions of their own (pltf-spec, pltf-client).
FOLDERS = {
    "pltf.reference_server": "reference_server",
    "pltf.fake_hardware": "fake_hardware",
    "pltf.conformance_tests": "conformance_tests",
    "pltf.fuzz": "fuzz",
    "pltf.stubgen": "clients/stubgen",
    "pltf.cli": "pltf_cli",
    "pltf.fixtures": "fixtures",
    "pltf.gui": "gui",
    "pltf.zoo": "zoo",
    "pltf.proxy": "proxy",
    "pltf.harness": "harness",
}


def _packages() -> tuple[list[str], dict[str, str]]:
    packages, package_dir = [], {}
    for name, folder in FOLDERS.items():
        packages.append(name)
        package_dir[name] = folder
        for sub in find_packages(folder):
            packages.append(f"{name}.{sub}")
    return packages, package_dir


class OptionalBuildExt(build_ext):
    """A failed extension build is a warning: the Python fallbacks run instead."""

    def run(self) -> None:
        try:
            super().run()
        except Exception as exc:
            print(f"warning: C extensions not built ({exc}); the Python fallbacks run", file=sys.stderr)

    def build_extension(self, ext: Extension) -> None:
        try:
            super().build_extension(ext)
        except Exception as exc:
            print(f"warning: {ext.name} not built ({exc}); its Python fallback runs", file=sys.stderr)


FLAGS = ["-O2", "-ffp-contract=off"]
EXTENSIONS = [
    Extension(
        f"pltf.reference_server.world.{name}",
        [f"reference_server/world/{name}.c"],
        extra_compile_args=FLAGS,
        optional=True,
    )
    for name in ("_raycast", "_geometry")
] + [
    # pltf proxy's forwarding loop (proxy/_forward.c); without it the proxy forwards with Python threads
    Extension("pltf.proxy._forward", ["proxy/_forward.c"], extra_compile_args=["-O2"], optional=True),
    # the fuzzer's drawing core (fuzz/_draw.c); without it the cases are drawn in Python (another stream)
    Extension("pltf.fuzz._draw", ["fuzz/_draw.c"], extra_compile_args=["-O2"], optional=True),
    # the fuzzer's plain single (fuzz/_singles.c, Linux: epoll); without it fuzz/flight.py's Single runs
    Extension("pltf.fuzz._singles", ["fuzz/_singles.c"], extra_compile_args=["-O2"], optional=True),
]

PACKAGES, PACKAGE_DIR = _packages()
setup(
    packages=PACKAGES,
    package_dir=PACKAGE_DIR,
    ext_modules=[] if os.environ.get("PLTF_NO_EXTENSIONS") == "1" else EXTENSIONS,
    cmdclass={"build_ext": OptionalBuildExt},
)
