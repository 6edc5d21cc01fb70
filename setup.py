"""The C extensions; everything else about the package is in pyproject.toml.

Inner loops in C: the ray caster (reference_server/world/raycast.py) and segments_clear (geometry.py). Both
modules fall back to their numpy versions when the extensions are missing. -ffp-contract=off: no fused
multiply-add, so the C loops round every product as numpy does (the tests hold them to numpy bit for bit).
"""

from setuptools import Extension, setup

FLAGS = ["-O2", "-ffp-contract=off"]

setup(
    ext_modules=[
        Extension(f"reference_server.world.{name}", [f"reference_server/world/{name}.c"], extra_compile_args=FLAGS)
        for name in ("_raycast", "_geometry")
    ]
)
