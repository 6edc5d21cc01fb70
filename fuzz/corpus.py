"""The corpus directory: where a campaign resumes from.

Layout: ``progress.json`` (per seed, the next case index and the signatures of the findings already
reported) and ``cases/<sha1>.json`` (inputs that reached something new: mutation seeds for later runs).
Bounded: at most ``MAX_CASES`` files are kept.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from pltf.fuzz.case import Case

MAX_CASES = 5_000
MAX_CASE_BYTES = 1 << 16


class Corpus:
    def __init__(self, directory: Path | None) -> None:
        self.dir = directory
        self.progress: dict[str, Any] = {}
        self.count = 0
        if directory is not None:
            (directory / "cases").mkdir(parents=True, exist_ok=True)
            p = directory / "progress.json"
            if p.exists():
                self.progress = json.loads(p.read_text())
            self.count = sum(1 for _ in (directory / "cases").glob("*.json"))

    def load_cases(self) -> list[Case]:
        if self.dir is None:
            return []
        out = []
        for p in sorted((self.dir / "cases").glob("*.json"))[:MAX_CASES]:
            try:
                out.append(Case.from_json(json.loads(p.read_text())))
            except (ValueError, KeyError):
                continue
        return out

    def next_index(self, seed: int) -> int:
        return int(self.progress.get("seeds", {}).get(str(seed), 0))

    def known_findings(self) -> set[str]:
        return set(self.progress.get("findings", []))

    def add(self, case: Case) -> bool:
        if self.dir is None or self.count >= MAX_CASES or case.size > MAX_CASE_BYTES:
            return False
        digest = hashlib.sha1(b"".join(case.frames)).hexdigest()
        path = self.dir / "cases" / f"{digest}.json"
        if path.exists():
            return False
        path.write_text(json.dumps(case.to_json()))
        self.count += 1
        return True

    def save(self, seed: int, next_index: int, findings: set[str]) -> None:
        if self.dir is None:
            return
        seeds = dict(self.progress.get("seeds", {}))
        seeds[str(seed)] = next_index
        self.progress = {"seeds": seeds, "findings": sorted(findings | self.known_findings())}
        tmp = self.dir / "progress.json.tmp"
        tmp.write_text(json.dumps(self.progress, indent=2))
        tmp.replace(self.dir / "progress.json")
