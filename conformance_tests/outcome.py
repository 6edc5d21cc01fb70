"""How a case reports: exceptions for its outcome, and the rule that turns them into a verdict.

Rules:
- ``Fail`` - the target broke the case's requirement. The verdict follows the case's level: MUST -> FAIL,
  SHOULD -> NON-STRICT, MAY -> N/A (the target lacks an optional behaviour). ``TargetFailure`` subclasses
  (reply timeout, connection closed, undecodable reply) are Fails raised by the wire layer.
- ``Deviation`` (recorded with ``ctx.deviate``, never raised) - the target follows an alternative reading of an
  erratum. With the ``original`` profile an alternative the register marks ``accept`` gives NON-STRICT; every
  other deviation is graded like a Fail at the erratum's level (MAY deviations are informative only).
- ``Absurd`` - the target reported a value no platform can have (reported.py): FAIL whatever the case's level.
- ``NotApplicable`` - the target shows or declares that it lacks an optional feature.
- ``Inconclusive`` - the observation cannot tell pass from fail (noise, timing); the runner re-runs the case,
  except when it is ``BudgetSpent`` (the case's time budget ran out, pace.py).
- Anything else escaping a case is a harness ERROR.
"""

from __future__ import annotations

from dataclasses import dataclass

from pltf.conformance_tests.catalogue import Level, Verdict
from pltf.spec.errata import load_errata


class Outcome(Exception):
    """Base of the outcomes a case raises."""


class Fail(Outcome):
    def __init__(self, message: str, *, erratum: str | None = None, precondition: bool = False) -> None:
        super().__init__(message)
        self.erratum = erratum
        self.precondition = precondition


class TargetFailure(Fail):
    """Raised by the wire layer: the target misbehaved at the transport or codec level."""


class ReplyTimeout(TargetFailure):
    pass


class ConnectionClosed(TargetFailure):
    pass


class BadReply(TargetFailure):
    pass


class Absurd(TargetFailure):
    """The target reported a value no platform can have (NaN, an infinity, far out of range: reported.py, erratum
    E-WIRE-009). A FAIL whatever the case's level: what a case was to judge cannot be judged from it."""


class NoConnection(ConnectionClosed):
    """No working connection to the target could be made within the connect window (it is gone or answers nobody)."""


class Unreachable(Exception):
    """The target cannot be reached at all (exit status 2)."""


class NotApplicable(Outcome):
    pass


class Inconclusive(Outcome):
    pass


class BudgetSpent(Inconclusive):
    """The case's time budget ran out before the case could finish: a target too slow to judge (not re-run)."""


@dataclass(frozen=True)
class Deviation:
    """The target follows alternative ``reading`` (index into the erratum's alternatives) of ``erratum``."""

    erratum: str
    reading: int | None
    detail: str

    @property
    def reading_text(self) -> str:
        e = load_errata()[self.erratum]
        if self.reading is None or self.reading >= len(e.alternatives):
            return "a reading the errata register does not list"
        return e.alternatives[self.reading].reading

    def accepted_by_original(self) -> bool:
        e = load_errata()[self.erratum]
        return (
            self.reading is not None
            and self.reading < len(e.alternatives)
            and (e.alternatives[self.reading].accepted_by_original_profile)
        )

    def describe(self) -> str:
        return f"{self.erratum}: {self.detail} (follows: {self.reading_text})"


_BY_LEVEL = {Level.MUST: Verdict.FAIL, Level.SHOULD: Verdict.NON_STRICT, Level.MAY: Verdict.NA}
_RANK = [Verdict.PASS, Verdict.NA, Verdict.NON_STRICT, Verdict.INCONCLUSIVE, Verdict.FAIL, Verdict.ERROR]


def verdict_for_level(level: Level) -> Verdict:
    return _BY_LEVEL[level]


def deviation_verdict(dev: Deviation, profile: str) -> Verdict:
    """The verdict a deviation alone earns under ``profile`` ("strict" or "original")."""
    if profile == "original" and dev.accepted_by_original():
        return Verdict.NON_STRICT
    level = Level(load_errata()[dev.erratum].level)
    if level is Level.MAY:
        return Verdict.PASS  # informative: noted in the report
    return _BY_LEVEL[level]


def worst(*verdicts: Verdict) -> Verdict:
    return max(verdicts, key=_RANK.index, default=Verdict.PASS)
