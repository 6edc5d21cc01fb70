"""The fuzzer's launcher is the toolkit's one launcher, pltf.zoo.launch (issue 18): ``Launcher(template, host,
port, second_port)`` with the template's ``{port}``, ``{second_port}``, ``{ports}`` and ``{tmpdir}``, warm spares
for the minimiser (``spares``, ``no_spares``), ``output``, ``alive``, ``exit_code``, ``stop``, ``cleanup``. These
names stay importable from here for the fuzzer's modules."""

from __future__ import annotations

from pltf.zoo.launch import START_TIMEOUT, STARTED, Launcher, LaunchError

__all__ = ["STARTED", "START_TIMEOUT", "LaunchError", "Launcher"]
