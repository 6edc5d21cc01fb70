"""One worker of a parallel campaign: the ordinary campaign (``pltf.fuzz.engine``) against a target of its own,
plus what it shares with the others through the driver (``pltf.fuzz.parallel_view``).

Rules:
- The engine is not changed, only composed: the worker's corpus also hands every input that reached something
  new (a new (state, telegram, origin, outcome), the campaign's coverage key) to the driver; its knowledge also
  carries the inputs other workers found into the forked case generator (``pltf.fuzz.prefetch`` sends knowledge
  to the child with each window), where they join the mutation seeds (``pltf.fuzz.schedule``).
- An imported input is tagged with its worker (``Case.tags``, kept through every mutation), so the report can
  say per worker how many of its cases grew from another's inputs and what new coverage they reached.
- Findings go to the driver whole (the files of their directory); the signatures and culprits the driver kept
  come back, so a worker does not reproduce what another worker already did.
- Transport-agnostic: ``Link.exchange(events) -> messages`` is a pipe to the local driver (``pltf.fuzz.parallel``)
  or a queue inside a Ray actor (``pltf.fuzz.ray_fuzz``). The worker calls it from the campaign's tick.
"""

from __future__ import annotations

import collections
import hashlib
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Protocol

from pltf.fuzz.case import Case
from pltf.fuzz.corpus import MAX_CASE_BYTES, MAX_CASES, Corpus
from pltf.fuzz.engine import Campaign, HarnessError
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.options import Options, Stats
from pltf.fuzz.unit import Unit
from pltf.harness.launch import LaunchError

SEED_MIN = 9  # bytes of each frame of an imported input at least: header, length and id (guide 6.2)
SYNC_EVERY = 0.5  # s between exchanges with the driver
IMPORTS_SENT = 256  # imported inputs the generator child gets at most per window (the newest)
TAG = "from:w"  # Case.tags entry of an input imported from worker N: "from:wN"
STATE_TAG = "state:"  # ... and of the state the worker found it in: "state:('ready', 0)"


class Link(Protocol):
    def exchange(self, events: list[dict[str, Any]]) -> list[dict[str, Any]]:
        """Hand the driver ``events``; what it has for this worker."""
        ...


def worker_seed(seed: int, index: int) -> int:
    """Worker N of ``--seed S`` draws the stream of seed S+N: its finding is reproduced by ``pltf fuzz --seed S+N``
    alone."""
    return seed + index


def digest(case: Case) -> str:
    return hashlib.sha1(b"".join(case.frames)).hexdigest()


def seedable(case: Case) -> bool:
    """A mutator takes a seed's frames apart at header, length and id (``pltf.fuzz.mutate``: "the seed is valid
    traffic"): an input with an empty or shorter frame (a fragment a mutation cut) made the generator child raise
    (IndexError, an empty randrange) and ended its worker. Such inputs are not passed on as seeds."""
    return bool(case.frames) and all(len(f) >= SEED_MIN for f in case.frames)


def source_of(case: Case) -> int | None:
    return next((int(t[len(TAG) :]) for t in case.tags if t.startswith(TAG)), None)


@dataclass
class SharedKnowledge(Knowledge):
    """``Knowledge`` that also carries imported inputs to the forked generator (``light()`` key ``imports``)."""

    imports: list[tuple[int, Case]] = field(default_factory=list)
    pool: list[Case] = field(default_factory=list)  # the scheduler's mutation seeds (the same list)
    seen_import: int = -1  # in the generator child: the last import taken

    def light(self) -> dict[str, Any]:
        return super().light() | {"imports": tuple(self.imports[-IMPORTS_SENT:])}

    def update(self, light: dict[str, Any], documents: dict[str, bytes]) -> None:
        imports = light.pop("imports", ())
        for n, case in imports:
            if n > self.seen_import:
                self.pool.append(case)
                self.seen_import = n
        super().update(light, documents)

    def add(self, cases: list[Case]) -> None:
        for case in cases:
            if len(self.imports) < MAX_CASES:
                self.imports.append((len(self.imports), case))
                self.pool.append(case)  # a generator in a thread (no fork) draws from this list itself
        self.version += 1


class SharedCorpus(Corpus):
    """The worker's corpus; ``add`` (called at each new coverage key) also queues the input for the others."""

    def __init__(self, directory: Path | None, worker: WorkerCampaign) -> None:
        super().__init__(directory)
        self.worker = worker
        self.seen: set[str] = set()
        self.outgoing: list[dict[str, Any]] = []
        self.exported = 0

    def add(self, case: Case) -> bool:
        w = self.worker
        source = source_of(case)
        if source is not None:
            w.new_from[source] = w.new_from.get(source, 0) + 1
        key = digest(case)
        if case.size <= MAX_CASE_BYTES and key not in self.seen:
            self.seen.add(key)
            self.exported += 1
            self.outgoing.append({"case": case.to_json(), "state": list(w.plan.current)})
        return super().add(case)


class WorkerCampaign(Campaign):
    def __init__(self, opts: Options, index: int, link: Link) -> None:
        super().__init__(opts)
        self.worker, self.link = index, link
        self.shared_kb = SharedKnowledge(pool=self.sched.pool)
        self.kb = self.sched.kb = self.shared_kb
        self.shared = SharedCorpus(opts.corpus, self)
        self.corpus = self.shared
        self.imported: dict[int, int] = {}
        self.used: dict[int, int] = {}
        self.used_states: dict[int, collections.Counter[str]] = {}  # the states the imports used were found in
        self.new_from: dict[int, int] = {}
        self.imported_states: dict[int, set[str]] = {}
        self.events: list[dict[str, Any]] = [{"kind": "running"}]
        self.last_sync = 0.0
        self.on_tick = self.tick

    # ------------------------------------------------------------------ the exchange with the driver
    def tick(self, _stats: Stats | None = None, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self.last_sync < SYNC_EVERY:
            return
        self.last_sync = now
        if self.shared.outgoing:
            self.events.append({"kind": "corpus", "entries": self.shared.outgoing})
            self.shared.outgoing = []
        events, self.events = self.events, []
        if events:
            events[-1]["figures"] = self.snapshot()
        else:
            events = [{"kind": "figures", "figures": self.snapshot()}]
        for e in events:
            e["worker"] = self.worker
        for message in self.link.exchange(events):
            self.receive(message)

    def receive(self, message: dict[str, Any]) -> None:
        self.writer.signatures.update(message.get("signatures", ()))
        self.writer.culprits.update(c for c in message.get("culprits", ()) if c)
        if message.get("stop"):
            self.stop = True
        entries = message.get("corpus", ())
        if entries:
            self._import(int(message["source"]), entries)

    def _import(self, source: int, entries: list[dict[str, Any]]) -> None:
        seen = self.shared.seen
        fresh = []
        for e in entries:
            case = Case.from_json(e["case"])
            key = digest(case)
            if key in seen or not seedable(case):
                continue
            seen.add(key)
            state = str(tuple(e["state"]))
            fresh.append(replace(case, tags=(f"{TAG}{source}", f"{STATE_TAG}{state}")))
            self.imported_states.setdefault(source, set()).add(state)
        self.imported[source] = self.imported.get(source, 0) + len(fresh)
        if fresh:
            self.shared_kb.add(fresh)

    def _count(self, cases: list[Case], outcome: str) -> None:
        for c in cases:
            if c.tags:
                source = source_of(c)
                if source is not None:
                    self.used[source] = self.used.get(source, 0) + 1
                    state = next((t[len(STATE_TAG) :] for t in c.tags if t.startswith(STATE_TAG)), "?")
                    by_state = self.used_states.setdefault(source, collections.Counter())
                    by_state[state] += 1
        super()._count(cases, outcome)

    def snapshot(self) -> dict[str, Any]:
        st = self.stats
        return {
            "cases": st.cases,
            "seconds": round(st.elapsed, 3),
            "cases_per_second": round(st.rate, 1),
            "units": st.units,
            "batches": st.batches,
            "singles": st.singles,
            "probes": st.probes,
            "restarts": st.restarts,
            "origins": dict(st.origins),
            "telegrams": sorted(st.telegrams),
            "states": sorted([list(s) for s in st.states], key=str),
            "findings": len(st.findings),
            "unconfirmed": len(st.unconfirmed),
            "duplicates": st.duplicates,
            "coverage": len(self.coverage),
            "exported": self.shared.exported,
            "imported": _keyed(self.imported),
            "used": _keyed(self.used),
            "new_coverage_from": _keyed(self.new_from),
            "imported_states": {f"w{k}": sorted(v) for k, v in sorted(self.imported_states.items())},
            "used_states": {f"w{k}": dict(v) for k, v in sorted(self.used_states.items())},
        }

    # ------------------------------------------------------------------ findings go to the driver whole
    def failure(self, kind: str, reason: str, units: list[Unit], ok: bool, evidence: dict[str, Any]) -> None:
        st = self.stats
        found, unconfirmed, culprits = len(st.findings), len(st.unconfirmed), set(self.writer.culprits)
        super().failure(kind, reason, units, ok, evidence)
        culprit = next(iter(self.writer.culprits - culprits), None)
        for f in [*st.findings[found:], *st.unconfirmed[unconfirmed:]]:
            directory = Path(f["dir"])
            called = directory.name.split("-", 3)[-1] if directory.name.count("-") >= 3 else "batch"
            files = {p.name: p.read_bytes() for p in directory.iterdir() if p.is_file()}
            self.events.append({"kind": "finding", "finding": f, "files": files, "culprit": culprit, "called": called})
        if len(st.findings) > found or len(st.unconfirmed) > unconfirmed:
            self.tick(force=True)


def _keyed(counts: dict[int, int]) -> dict[str, int]:
    return {f"w{k}": v for k, v in sorted(counts.items()) if v}


def run_worker(opts: Options, index: int, link: Link) -> int:
    """The worker's campaign to its end; the last exchange says how it ended (done or failed)."""
    try:
        campaign = WorkerCampaign(opts, index, link)
    except (OSError, ValueError) as exc:
        link.exchange([{"kind": "failed", "worker": index, "error": str(exc)}])
        return 2
    try:
        code = campaign.run()
    except (HarnessError, LaunchError, OSError, RuntimeError) as exc:
        campaign.close()
        lines = str(exc).strip().splitlines() or [type(exc).__name__]
        why = lines[0] if len(lines) == 1 else f"{lines[0]} {lines[-1]}"  # a traceback's last line names it
        campaign.events.append({"kind": "failed", "error": why[:500]})
        campaign.tick(force=True)
        return 2
    campaign.events.append({"kind": "done", "code": code})
    campaign.tick(force=True)
    return code
