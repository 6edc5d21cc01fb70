"""Where a parallel campaign's report goes: ``--out`` as a single campaign writes it, the findings once.

Rules: every file is written atomically (a finding's directory is filled under a temporary name and renamed
into place; ``summary.json`` through a temporary file), so a reader never sees half a finding. A finding's
``finding.json`` also names the worker that found it and the worker's seed (``pltf fuzz --seed`` of that seed
alone draws the same cases).
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any

from pltf.fuzz.parallel_view import CampaignView


class Store:
    def __init__(self, out: Path) -> None:
        self.out = out
        self.written = 0

    def write_new(self, view: CampaignView) -> None:
        """The findings kept since the last call."""
        for kept in view.kept[self.written :]:
            f = kept.finding
            seed = view.workers[f["worker"]].seed
            f["dir"] = str(self._write(kept.name, kept.files, {"worker": f["worker"], "worker_seed": seed}))
        self.written = len(view.kept)

    def _write(self, name: str, files: dict[str, bytes], extra: dict[str, Any]) -> Path:
        final = self.out / name
        final.parent.mkdir(parents=True, exist_ok=True)
        tmp = final.parent / f".{final.name}.tmp-{os.getpid()}"
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir()
        for fname, data in files.items():
            if fname == "finding.json":
                data = (json.dumps(json.loads(data) | extra, indent=2, default=str) + "\n").encode()
            (tmp / Path(fname).name).write_bytes(data)
            if fname.endswith(".py"):
                (tmp / fname).chmod(0o755)
        shutil.rmtree(final, ignore_errors=True)
        tmp.rename(final)
        return final

    def summary(self, view: CampaignView) -> None:
        self.out.mkdir(parents=True, exist_ok=True)
        tmp = self.out / f".summary.json.tmp-{os.getpid()}"
        tmp.write_text(json.dumps(view.summary(), indent=2, default=str) + "\n")
        tmp.replace(self.out / "summary.json")
