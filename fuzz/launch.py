"""The fuzzer's launcher is the toolkit's one launcher, pltf.zoo.launch (issue 18): these names stay importable
from here for the fuzzer's modules (``Launcher(template, host, port, second_port)``; the template's ``{port}``,
``{second_port}``, ``{ports}`` and ``{tmpdir}`` as before)."""

from __future__ import annotations

from pltf.zoo.launch import START_TIMEOUT, STARTED, Launcher, LaunchError

__all__ = ["STARTED", "START_TIMEOUT", "LaunchError", "Launcher"]
