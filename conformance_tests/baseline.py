"""The known-failures baseline (after the protobuf conformance runner's failure list).

Format: one case id per line, optionally followed by the verdicts it is expected to have (default: any verdict
but PASS) and a ``#`` comment::

    6.2/framing/huge-length  NON-STRICT   # firmware 2.265 waits for the data
    6.3/CMD_SET_DIGOUT/effect             # relay board missing on this platform

Rules: a listed case that does not pass is an expected failure and does not fail the run; a listed case that
PASSes (or whose verdict is not among the listed ones), or an id the catalogue does not know, is a stale entry
and fails the run, so the list only ever shrinks. Cases listed but not selected in this run are ignored.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pltf.conformance_tests.catalogue import REGISTRY, Verdict

NOT_PASS = frozenset(v for v in Verdict if v not in (Verdict.PASS, Verdict.SKIPPED))


class BaselineError(ValueError):
    pass


@dataclass
class Baseline:
    entries: dict[str, frozenset[Verdict]] = field(default_factory=dict)
    source: str = ""

    @classmethod
    def parse(cls, text: str, source: str = "<baseline>") -> Baseline:
        entries: dict[str, frozenset[Verdict]] = {}
        for n, raw in enumerate(text.splitlines(), 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            case_id, *verdicts = line.split()
            try:
                expected = frozenset(Verdict(v) for v in verdicts) if verdicts else NOT_PASS
            except ValueError:
                raise BaselineError(f"{source}:{n}: unknown verdict in {raw.strip()!r}") from None
            if Verdict.PASS in expected:
                raise BaselineError(f"{source}:{n}: a baseline lists failures, not PASS")
            entries[case_id] = expected
        return cls(entries, source)

    @classmethod
    def load(cls, path: str | Path) -> Baseline:
        try:
            return cls.parse(Path(path).read_text(encoding="utf-8"), str(path))
        except OSError as exc:
            raise BaselineError(f"cannot read baseline {path}: {exc}") from None

    def expects(self, result: Any) -> bool:
        expected = self.entries.get(result.case.id)
        return expected is not None and result.verdict in expected

    def stale(self, ran: Mapping[str, Any]) -> list[str]:
        """The entries that no longer hold, each with the reason."""
        out = []
        for case_id, expected in self.entries.items():
            if case_id not in REGISTRY:
                out.append(f"{case_id}: no such case in the catalogue")
                continue
            result = ran.get(case_id)
            if result is None or result.verdict is Verdict.SKIPPED:
                continue
            if result.verdict not in expected:
                out.append(
                    f"{case_id}: expected {'/'.join(sorted(expected))}, got {result.verdict} - "
                    "remove or update the entry"
                )
        return out

    @staticmethod
    def render(results: Iterable[Any]) -> str:
        """A baseline that expects exactly the current failures (``--write-baseline``)."""
        lines = ["# known failures: case id, expected verdict(s), comment"]
        for r in results:
            if r.verdict in NOT_PASS:
                lines.append(f"{r.case.id}  {r.verdict}  # {r.message.splitlines()[0][:100] if r.message else ''}")
        return "\n".join(lines) + "\n"
