"""The live view: cases/s, coverage of telegrams and states, findings (rich)."""

from __future__ import annotations

from typing import Any

from rich.console import Console
from rich.live import Live
from rich.table import Table

from pltf.fuzz.generate import request_defs


def render(stats: Any, title: str) -> Table:
    table = Table(title=title, show_header=False, box=None)
    table.add_column(justify="right", style="bold")
    table.add_column()
    n_tel = len(request_defs())
    covered = sum(1 for t in stats.telegrams if not t.startswith("id "))
    ids = sum(1 for t in stats.telegrams if t.startswith("id "))
    profile = getattr(stats, "profile", None)
    if profile:  # what the opening phase learnt (pltf.fuzz.profile)
        table.add_row("target", str(profile.get("summary", "")))
    table.add_row("elapsed", f"{stats.elapsed:,.1f} s")
    table.add_row("cases", f"{stats.cases:,}  ({stats.rate:,.0f}/s)")
    batches, singles = getattr(stats, "batches", 0), getattr(stats, "singles", 0)
    table.add_row(
        "units", f"{stats.units:,} ({batches:,} batches, {singles:,} single, {getattr(stats, 'probes', 0):,} probes)"
    )
    if hasattr(stats, "pipelined"):
        off = " - off on a port: the target turned pipelined clients away" if stats.turn_aways else ""
        table.add_row("pipelined", f"{stats.pipelined:,} units{off}")
        release = ", ".join(f"{ms:g}" for ms in stats.release_ms)
        dear = f"; dear: batches kept, {stats.skipped:,} singles skipped" if stats.dear else ""
        if stats.ways:
            dear += " (measured: " + ", ".join(f"{k} {v:,.0f}/s" for k, v in stats.ways.items()) + ")"
        table.add_row("connections", f"{stats.not_admitted:,} not served (run again); release {release} ms{dear}")
    table.add_row("telegrams", f"{min(covered, n_tel)}/{n_tel} request telegrams, {ids} other ids")
    if hasattr(stats, "state_targets"):
        table.add_row("states", f"{len(stats.states)}/{stats.state_targets} (state, mode) reached")
    top = ", ".join(f"{k} {v:,}" for k, v in stats.origins.most_common(6))
    table.add_row("origins", top)
    style = "bold red" if stats.findings else "green"
    table.add_row(
        "findings",
        f"[{style}]{len(stats.findings)}[/{style}]"
        + "".join(f"\n{f['kind']}: {f['dir']}" for f in stats.findings[-5:]),
    )
    unconfirmed = getattr(stats, "unconfirmed", [])
    if unconfirmed:
        table.add_row(
            "unconfirmed",
            f"[yellow]{len(unconfirmed)}[/yellow] (did not happen again when replayed; "
            "not findings)" + "".join(f"\n{f['kind']}: {f['dir']}" for f in unconfirmed[-3:]),
        )
    return table


class LiveView:
    """A rich Live display when stdout is a terminal; otherwise a line every few seconds (or nothing)."""

    def __init__(self, title: str, quiet: bool = False) -> None:
        self.title, self.quiet = title, quiet
        self.console = Console(stderr=True)
        self.live: Live | None = None
        self._last_line = 0.0

    def __enter__(self) -> LiveView:
        if not self.quiet and self.console.is_terminal:
            self.live = Live(console=self.console, refresh_per_second=4, transient=False)
            self.live.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.live is not None:
            self.live.__exit__(None, None, None)

    def update(self, stats: Any) -> None:
        if self.live is not None:
            self.live.update(render(stats, self.title))
        elif not self.quiet and stats.elapsed - self._last_line >= 5.0:
            self._last_line = stats.elapsed
            self.console.print(
                f"{stats.elapsed:6.1f} s  {stats.cases:,} cases ({stats.rate:,.0f}/s)  "
                f"{len(stats.findings)} findings, {len(getattr(stats, 'unconfirmed', []))} "
                "unconfirmed"
            )

    def final(self, stats: Any) -> None:
        if not self.quiet:
            self.console.print(render(stats, self.title + " - done"))
