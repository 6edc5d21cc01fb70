"""The seam between the platform and the task interpreter (guide 4.3 Mode Program, 4.5, 6.5 Program).

Rules:
- The platform owns one ``Program`` as ``Platform.program``, built once by ``Platform(..., program=factory)``
  with ``factory(platform) -> Program``; the default is ``NoProgram``. The task interpreter
  (reference_server/tasks/) plugs in here; nothing else of the platform knows it.
- In motion mode MODE_MOTION_PROGRAM the operation commands drive it, after the state chart allowed them and
  after the platform did its own part on the motion: CMD_START -> ``start(now)`` (the motion was stopped),
  CMD_BREAK -> ``pause(now)`` (the motion is held), CMD_CONTINUE -> ``resume(now)`` (the motion goes on),
  CMD_STOP -> ``stop(now)`` (the motion was stopped). Leaving Running or Breaked any other way (emergency
  stop, drive fault, CMD_SHUTDOWN_PLTF, CMD_EXIT) also calls ``stop(now)``.
- ``tick(now)`` is called once per control period (50 Hz simulated), in every state and mode, at the start of
  the period (before the motion step), so a command the program gives takes effect in the same period.
- ``start`` takes the program document active at that moment (``platform.documents.get(DocumentKind.PROGRAM)``).
- A program logs through ``platform.log(level, text)`` (the server log and GET_DEBUG_DATA's protocol queue)
  and acts only through the platform model; it never raises into the platform (a failing task is its own
  business). Time is the simulated ``now``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from pltf.reference_server.platform import Platform


class Program(Protocol):
    def start(self, now: float) -> None:
        """CMD_START in MODE_MOTION_PROGRAM: run the active program from its beginning."""

    def pause(self, now: float) -> None:
        """CMD_BREAK: freeze the program (its waits and delays stand still)."""

    def resume(self, now: float) -> None:
        """CMD_CONTINUE after CMD_BREAK."""

    def stop(self, now: float) -> None:
        """CMD_STOP, or the platform left Running/Breaked: end every task."""

    def tick(self, now: float) -> None:
        """One control period."""


ProgramFactory = Callable[["Platform"], Program]
Log = Callable[[int, str], None]


class NoProgram:
    """The default: no task interpreter is plugged in, so CMD_START in MODE_MOTION_PROGRAM does nothing."""

    def __init__(self, log: Log) -> None:
        self._log = log

    def start(self, now: float) -> None:
        self._log(logging.WARNING, "no program loaded: MODE_MOTION_PROGRAM runs nothing")

    def pause(self, now: float) -> None:
        pass

    def resume(self, now: float) -> None:
        pass

    def stop(self, now: float) -> None:
        pass

    def tick(self, now: float) -> None:
        pass


def no_program(platform: Platform) -> Program:
    return NoProgram(platform.log)
