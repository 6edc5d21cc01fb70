"""The live console view (rich): a progress bar while the cases run, every non-PASS verdict as it happens, then
the summary table by guide chapter, the coverage table and the baseline's stale entries."""

from __future__ import annotations

from collections.abc import Sequence

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TaskID, TextColumn, TimeElapsedColumn
from rich.table import Table

from pltf.conformance_tests.catalogue import Case, Verdict
from pltf.conformance_tests.reports import ORDER, first_line, summary_rows
from pltf.conformance_tests.runner import CaseResult, RunResult
from pltf.conformance_tests.target import Config

STYLE = {
    Verdict.PASS: "green",
    Verdict.FAIL: "bold red",
    Verdict.NON_STRICT: "yellow",
    Verdict.NA: "cyan",
    Verdict.INCONCLUSIVE: "magenta",
    Verdict.ERROR: "bold white on red",
    Verdict.SKIPPED: "dim",
}


class ConsoleReporter:
    def __init__(self, console: Console | None = None, *, verbose: bool = False, show_coverage: bool = True) -> None:
        self.console = console or Console(stderr=False)
        self.verbose = verbose
        self.show_coverage = show_coverage
        self._progress: Progress | None = None
        self._task: TaskID | None = None

    def on_start(self, config: Config, cases: Sequence[Case], gate: list[str]) -> None:
        c = self.console
        c.print(
            f"[bold]pltf conform[/] {config.host}:{config.port}"
            + (f" (+{config.second_port})" if config.second_port else "")
            + f"  profile {config.profile}, tier {config.tier.name.lower()}, time scale {config.time_scale:g}, "
            f"{len(cases)} cases"
        )
        for line in gate:
            c.print(f"[bold yellow]![/] {line}")
        self._progress = Progress(
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            console=c,
            transient=True,
        )
        self._progress.start()
        self._task = self._progress.add_task("starting", total=len(cases))

    def on_case_start(self, case: Case) -> None:
        if self._progress is not None and self._task is not None:
            self._progress.update(self._task, description=case.id[:60].ljust(60))

    def on_case_end(self, result: CaseResult) -> None:
        if self._progress is not None and self._task is not None:
            self._progress.advance(self._task)
        if result.verdict is not Verdict.PASS or self.verbose:
            style = STYLE[result.verdict]
            msg = first_line(result.message)
            self.console.print(
                f"[{style}]{result.verdict:>12}[/] {result.case.id} [dim]({result.case.level})[/] {msg[:160]}",
                highlight=False,
            )

    def on_finish(self, run: RunResult) -> None:
        if self._progress is not None:
            self._progress.stop()
        c = self.console
        if run.harness_error:
            c.print(f"[bold red]harness error:[/] {run.harness_error}")
            return
        table = Table(title="Results by guide section", show_lines=False)
        table.add_column("section")
        table.add_column("")
        for v in ORDER:
            table.add_column(v.value, justify="right", style=STYLE[v])
        table.add_column("cases", justify="right")
        for row in summary_rows(run.results):
            table.add_row(
                row.section,
                row.title,
                *(str(row.counts[v] or "") for v in ORDER),
                str(row.total),
                end_section=row.section == "all",
            )
        c.print(table)
        if self.show_coverage:
            cov = Table(title="Spec coverage")
            for col in ("metric", "covered", "total", "%", "missing (first)"):
                cov.add_column(col)
            for m in run.target.coverage.metrics():
                cov.add_row(
                    m.name + ("" if m.enforced else " (informative)"),
                    str(m.covered),
                    str(m.total),
                    f"{m.percent:.1f}",
                    ", ".join(m.missing[:3]),
                )
            c.print(cov)
        expected = [r for r in run.results if r.expected_failure]
        if expected:
            c.print(f"{len(expected)} failure(s) expected by the baseline")
        for line in run.stale:
            c.print(f"[bold red]stale baseline entry:[/] {line}")
        for line in run.notes:
            c.print(f"[bold]note:[/] {line}")
        c.print(f"{len(run.results)} cases in {run.duration:.1f} s - exit status {run.exit_code}")
