"""The driver's view of a parallel campaign (``pltf fuzz --jobs N``, ``--ray``): what every worker reported, the
corpus entries to pass on, the findings once each.

Rules:
- Sans-IO: events (plain dicts, ``pltf.fuzz.parallel_worker``) go in through ``take``, messages for the workers
  come out of ``outbox``; the caller moves them (processes and pipes in ``pltf.fuzz.parallel``, Ray actors in
  ``pltf.fuzz.ray_fuzz``) and gives ``now``.
- What one worker found interesting goes to every other worker (AFL++'s main/secondary instances, libFuzzer's
  ``-jobs``); a receiver drops what it has already.
- A finding is kept once: the first with its signature (``pltf.fuzz.findings``: kind and the ids of the minimal
  frames) or its culprit (kind, telegram, origin) wins; a later one from another worker is a duplicate, counted.
  The signatures and culprits kept go to every worker, so a worker does not reproduce what another already did.
- ``--max-findings N`` holds for the campaign: workers are stopped at the N-th, and a finding another worker
  brings in after it (found at the same time) is counted, not kept.
- The attributes the live view reads (``pltf.fuzz.view.render``) are the sums and unions over the workers.
"""

from __future__ import annotations

import collections
from dataclasses import dataclass, field
from typing import Any

from pltf.fuzz.report import slug


@dataclass
class WorkerView:
    """The last figures one worker sent (``pltf.fuzz.parallel_worker.snapshot``) and what became of it."""

    index: int
    seed: int
    figures: dict[str, Any] = field(default_factory=dict)
    status: str = "starting"  # starting, running, done, failed, lost, stopped (--max-findings were kept)
    error: str = ""
    starts: int = 1  # a worker lost and started again (``--ray``) counts each start
    where: str = "local"  # the Ray node of its actor (its target runs there)


@dataclass
class Kept:
    """A finding as the driver keeps it: the worker's description and its files, once."""

    finding: dict[str, Any]
    files: dict[str, bytes]
    name: str


class CampaignView:
    def __init__(self, seeds: list[int], state_targets: int, started: float, max_findings: int | None = None) -> None:
        self.workers = [WorkerView(k, s) for k, s in enumerate(seeds)]
        self.state_targets = state_targets
        self.started = started
        self.now = started
        self.findings: list[dict[str, Any]] = []
        self.unconfirmed: list[dict[str, Any]] = []
        self.kept: list[Kept] = []  # written by the caller (``pltf.fuzz.parallel_store``)
        self.signatures: set[str] = set()
        self.culprits: set[str] = set()
        self.duplicates = 0  # findings another worker had already reported
        self.max_findings = max_findings
        self.beyond_max = 0  # findings that came in once --max-findings were kept (workers found them at once)
        self.relayed = 0  # corpus entries passed on
        self.lost: list[str] = []  # workers that died (or their node) and what became of them
        self.outbox: dict[int, list[dict[str, Any]]] = collections.defaultdict(list)

    # ------------------------------------------------------------------ events from the workers
    def take(self, event: dict[str, Any], now: float) -> None:
        self.now = now
        w = self.workers[event["worker"]]
        kind = event["kind"]
        if "figures" in event:
            w.figures = event["figures"]
        if kind == "corpus":
            self._relay(w.index, event["entries"])
        elif kind == "finding":
            self._finding(event)
        elif kind == "running":
            w.status = "running"
        elif kind == "done":
            w.status = "done"
        elif kind == "failed":
            w.status, w.error = "failed", event["error"]

    def _relay(self, source: int, entries: list[dict[str, Any]]) -> None:
        for other in self.workers:
            if other.index != source and other.status in ("starting", "running"):
                self.outbox[other.index].append({"corpus": entries, "source": source})
        self.relayed += len(entries)

    def _finding(self, event: dict[str, Any]) -> None:
        f = dict(event["finding"], worker=event["worker"])
        if not f["confirmed"]:
            name = f"unconfirmed/w{event['worker']}-{len(self.unconfirmed) + 1:03d}-{slug(f['kind'])}"
            self.unconfirmed.append(f)
            self.kept.append(Kept(f, event["files"], name))
            return
        if f["signature"] in self.signatures or event.get("culprit") in self.culprits:
            self.duplicates += 1
            return
        if self.max_findings is not None and len(self.findings) >= self.max_findings:
            self.beyond_max += 1
            return
        self.signatures.add(f["signature"])
        if event.get("culprit"):
            self.culprits.add(event["culprit"])
        self.findings.append(f)
        name = f"finding-{len(self.findings):03d}-{f['kind']}-{slug(event.get('called', 'batch'))}"
        self.kept.append(Kept(f, event["files"], name))
        for other in self.workers:
            self.outbox[other.index].append({"signatures": [f["signature"]], "culprits": [event.get("culprit")]})

    def lose(self, index: int, why: str, again: bool) -> None:
        """A worker (or its node) died: reported; ``again`` when it is started anew."""
        w = self.workers[index]
        self.lost.append(f"worker {index} (seed {w.seed}): {why}; " + ("started again" if again else "not replaced"))
        if again:
            w.starts += 1
            w.status = "starting"
            self.outbox[index] = [
                {"signatures": sorted(self.signatures), "culprits": sorted(c for c in self.culprits if c)}
            ]
        else:
            w.status, w.error = "lost", why

    def enough(self) -> bool:
        """``--max-findings`` were kept."""
        return self.max_findings is not None and len(self.findings) >= self.max_findings

    def cut(self, index: int) -> None:
        """A worker still busy once ``--max-findings`` were kept is ended (not lost)."""
        if self.workers[index].status in ("starting", "running"):
            self.workers[index].status = "stopped"

    def drain(self, index: int) -> list[dict[str, Any]]:
        return self.outbox.pop(index, [])

    # ------------------------------------------------------------------ what the live view reads
    def _sum(self, name: str) -> int:
        return sum(int(w.figures.get(name, 0)) for w in self.workers)

    @property
    def elapsed(self) -> float:
        return self.now - self.started

    @property
    def cases(self) -> int:
        return self._sum("cases")

    @property
    def rate(self) -> float:
        return self.cases / self.elapsed if self.elapsed > 0 else 0.0

    @property
    def units(self) -> int:
        return self._sum("units")

    @property
    def batches(self) -> int:
        return self._sum("batches")

    @property
    def singles(self) -> int:
        return self._sum("singles")

    @property
    def probes(self) -> int:
        return self._sum("probes")

    @property
    def telegrams(self) -> set[str]:
        return {t for w in self.workers for t in w.figures.get("telegrams", ())}

    @property
    def states(self) -> set[tuple[str, int | None]]:
        return {tuple(s) for w in self.workers for s in w.figures.get("states", ())}

    @property
    def origins(self) -> collections.Counter[str]:
        total: collections.Counter[str] = collections.Counter()
        for w in self.workers:
            total.update(w.figures.get("origins", {}))
        return total

    def summary(self) -> dict[str, Any]:
        """``summary.json`` of the whole campaign: the sums, the findings once, and each worker's coverage."""
        return {
            "cases": self.cases,
            "seconds": round(self.elapsed, 3),
            "cases_per_second": round(self.rate, 1),
            "origins": dict(self.origins),
            "telegrams": sorted(self.telegrams),
            "states": sorted(str(x) for x in self.states),
            "findings": self.findings,
            "unconfirmed": self.unconfirmed,
            "duplicates_across_workers": self.duplicates,
            "beyond_max_findings": self.beyond_max,
            "corpus_relayed": self.relayed,
            "lost_workers": self.lost,
            "workers": [
                {"worker": w.index, "seed": w.seed, "status": w.status, "starts": w.starts, "error": w.error}
                | {"where": w.where}
                | w.figures
                for w in self.workers
            ],
        }
