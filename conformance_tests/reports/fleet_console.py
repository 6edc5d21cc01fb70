"""The fleet's live console view: each target's non-PASS verdicts as they happen, tagged with its name (runs in
threads print through one lock), then a table per target and the cases whose verdicts differ between targets."""

from __future__ import annotations

import threading
from collections.abc import Sequence
from typing import Any

from rich.console import Console
from rich.table import Table

from pltf.conformance_tests.catalogue import Verdict
from pltf.conformance_tests.fleet import FleetTarget, TargetRun
from pltf.conformance_tests.reports import ORDER, first_line
from pltf.conformance_tests.reports.console import STYLE
from pltf.conformance_tests.reports.matrix import rows


class FleetConsole:
    def __init__(self, console: Console, *, verbose: bool = False) -> None:
        self.console = console
        self.verbose = verbose
        self._lock = threading.Lock()

    def on_start(self, targets: Sequence[FleetTarget], how: str) -> None:
        self.console.print(f"[bold]pltf conform[/] a fleet of {len(targets)} targets ({how})")
        for t in targets:
            second = f" (+{t.second_port})" if t.second_port else ""
            self.console.print(
                f"  {t.name}: {t.address}{second}  profile {t.profile}, time scale {t.time_scale:g}"
                + (", a simulator" if t.target_is_simulator else ", --allow-motion" if t.allow_motion else ""),
                highlight=False,
            )

    def on_case_end(self, name: str, result: Any) -> None:
        """A finished case of target ``name`` (a CaseResult; called from the target's thread)."""
        if result.verdict is Verdict.PASS and not self.verbose:
            return
        style = STYLE[result.verdict]
        with self._lock:
            self.console.print(
                f"[bold]{name}[/] [{style}]{result.verdict}[/] {result.case.id} {first_line(result.message)[:140]}",
                highlight=False,
            )

    def on_target_end(self, run: TargetRun) -> None:
        with self._lock:
            self.console.print(f"[bold]{run.name}[/] done: exit status {run.exit_code} {run.error}", highlight=False)

    def on_finish(self, runs: Sequence[TargetRun], code: int) -> None:
        c = self.console
        table = Table(title="Results by target")
        table.add_column("target")
        for v in ORDER:
            table.add_column(v.value, justify="right", style=STYLE[v])
        table.add_column("exit", justify="right")
        for r in runs:
            n = r.report.get("counts", {})
            table.add_row(r.name, *(str(n.get(v.value) or "") for v in ORDER), str(r.exit_code))
        c.print(table)
        differing = [row for row in rows(runs) if row.differs]
        if differing:
            diff = Table(title=f"{len(differing)} case(s) where the targets differ")
            diff.add_column("case")
            for r in runs:
                diff.add_column(r.name)
            diff.add_column("named")
            for row in differing:
                cells = [row.cells[r.name] for r in runs]
                diff.add_row(row.case, *(x.verdict if x else "-" for x in cells), "; ".join(row.named())[:200])
            c.print(diff)
        for r in runs:
            d = r.report.get("differential")
            if d is not None:
                what = d["error"] or f"{len(d['fields'])} field(s) differ from the reference server"
                c.print(f"differential {r.name}: {what}", highlight=False)
        c.print(f"{len(runs)} targets - exit status {code}")
