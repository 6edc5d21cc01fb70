"""In-process fuzzing of the codec and the XML validation: no sockets, full speed.

Rules:
- The same case stream as the network campaign (``pltf.fuzz.schedule.Scheduler``), plus mutated reply frames
  (from ``pltf.spec.strategies``-shaped telegrams encoded honestly, then mutated) and the XML attacks.
- Oracle (h11's fuzz invariant, spec/errors.py): ``TelegramDecoder``/``decode_frame`` raise only
  ``RemoteProtocolError``, however the bytes are split; ``validate_document`` raises only ``DocumentError``;
  no call takes longer than the deadline (a SIGALRM interrupts Python-level loops; C code is timed).
- A finding is the input bytes and the exception; its reproducer replays it in-process (and, given
  ``--target``, over TCP).
"""

from __future__ import annotations

import json
import math
import random
import signal
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

from pltf.fuzz import mutate, xml_attacks
from pltf.fuzz.case import Case
from pltf.fuzz.engine import Stats
from pltf.fuzz.generate import _valid_scalar
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.report import slug
from pltf.fuzz.schedule import Scheduler
from pltf.spec import errors
from pltf.spec.codec import REPLIES, TelegramDecoder, decode_frame, encode
from pltf.spec.documents import DocumentError, DocumentKind, validate_document
from pltf.spec.model import FieldDef

_SCRIPT = '''#!/usr/bin/env python3
"""Reproducer of a pltf fuzz --in-process finding: {what}

Run from the repository root: python {name}  (exit 1 when the failure happens again, 0 when it does not)
"""
import sys
import time

sys.path.insert(0, ".")
DATA = bytes.fromhex({data!r})
TARGET = {target!r}
DEADLINE = {deadline!r}


def main():
    from pltf.spec import errors
    from pltf.spec.codec import decode_frame
    from pltf.spec.documents import DocumentError, validate_document

    t0 = time.monotonic()
    try:
        if TARGET.startswith("validate_document:"):
            validate_document(TARGET.split(":", 1)[1], DATA)
        else:
            decode_frame(DATA, TARGET.split(":", 1)[1])
    except (errors.RemoteProtocolError, DocumentError):
        pass
    except Exception as exc:
        print("reproduced:", type(exc).__name__, exc)
        return 1
    if time.monotonic() - t0 > DEADLINE:
        print("reproduced: took", time.monotonic() - t0, "s")
        return 1
    print("not reproduced")
    return 0


if __name__ == "__main__":
    sys.exit(main())
'''


MAX_FRAMES = 16
XML_SHARE = 0.1  # of cases that also validate a hostile document


class Timeout(Exception):
    """Raised by the SIGALRM handler inside a call that overran the deadline."""


def _alarm(signum: int, frame: Any) -> None:
    raise Timeout


class InProcessCampaign:
    def __init__(
        self, seed: int, duration: float, out: Path, max_cases: int | None, deadline: float, command: str
    ) -> None:
        self.seed, self.duration, self.out = seed, duration, out
        self.max_cases, self.deadline, self.command = max_cases, deadline, command
        self.stats = Stats()
        self.kb = Knowledge()
        self.sched = Scheduler(seed, frozenset(), self.kb)  # nothing is dangerous in-process
        self.signatures: set[str] = set()
        self._seen_docs: set[tuple[str, int]] = set()

    # ------------------------------------------------------------------ the targets
    def _decode_stream(self, data: bytes, rng: random.Random, direction: str) -> None:
        dec = TelegramDecoder(direction)  # type: ignore[arg-type]
        pos = 0
        while pos < len(data):
            step = rng.choice((1, 7, 64, len(data)))
            dec.receive_data(data[pos : pos + step])
            pos += step
            for _ in dec:
                pass
        dec.receive_data(b"")
        for _ in dec:
            pass

    def _check(
        self, target: str, data: bytes, call: Callable[[], object], expected: tuple[type[BaseException], ...]
    ) -> None:
        signal.setitimer(signal.ITIMER_REAL, self.deadline)
        t0 = time.monotonic()
        try:
            call()
        except expected:
            pass
        except Timeout:
            self._finding("hang", target, data, f"interrupted after {self.deadline} s")
        except Exception as exc:
            self._finding(type(exc).__name__, target, data, "".join(traceback.format_exception(exc))[-2000:])
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
        if time.monotonic() - t0 > self.deadline:
            self._finding("slow", target, data, f"took {time.monotonic() - t0:.2f} s")

    def one(self, i: int) -> None:
        case = self.sched.case(i)
        rng = random.Random(f"{self.seed}:{i}:ip")
        data = b"".join(case.frames[:MAX_FRAMES])  # a flood's thousand copies add nothing in-process
        self._check(
            "decode_frame:request",
            data,
            lambda: self._decode_stream(data, rng, "request"),
            (errors.RemoteProtocolError,),
        )
        self._check("decode_frame:request", data, lambda: decode_frame(data, "request"), (errors.RemoteProtocolError,))
        r = rng.random()
        if r < 0.3:
            reply = Case((reply_frame(rng),), "reply", "reply")
            name = rng.choice(list(mutate.MUTATORS))
            if name not in ("mut.bytewise", "mut.slow", "mut.half_close"):
                reply = mutate.MUTATORS[name][1](reply, rng)
            rdata = reply.data
            self._check(
                "decode_frame:reply",
                rdata,
                lambda: self._decode_stream(rdata, rng, "reply"),
                (errors.RemoteProtocolError,),
            )
        if r > 1 - XML_SHARE:
            kind = rng.choice(("map", "roadmap", "program"))
            _, doc = xml_attacks.attack(kind, rng)
            if rng.random() < 0.5:
                doc = _mutate_bytes(doc, rng)
            elif len(doc) > 1 << 16:  # the big documents are built once and cached: validate each once
                if (kind, id(doc)) in self._seen_docs:
                    doc = doc[: 1 << 12]
                self._seen_docs.add((kind, id(doc)))
            self._check(
                f"validate_document:{kind}", doc, lambda: validate_document(DocumentKind(kind), doc), (DocumentError,)
            )
        self.stats.cases += 1
        self.stats.origins[case.origin] += 1
        self.stats.telegrams.add(case.telegram)

    def run(self, on_tick: Callable[[Stats], None] | None = None) -> int:
        old = signal.signal(signal.SIGALRM, _alarm)
        end = time.monotonic() + self.duration
        i, last = 0, 0.0
        try:
            while time.monotonic() < end and (self.max_cases is None or i < self.max_cases):
                self.one(i)
                i += 1
                if on_tick is not None and time.monotonic() - last > 0.25:
                    last = time.monotonic()
                    on_tick(self.stats)
        finally:
            signal.signal(signal.SIGALRM, old)
        return 1 if self.stats.findings else 0

    def _finding(self, kind: str, target: str, data: bytes, detail: str) -> None:
        signature = f"{kind}:{target}:{detail.strip().splitlines()[-1][:80] if detail.strip() else ''}"
        if signature in self.signatures:
            self.stats.duplicates += 1
            return
        self.signatures.add(signature)
        d = self.out / f"finding-{len(self.stats.findings) + 1:03d}-inprocess-{slug(kind)}-{slug(target)}"
        d.mkdir(parents=True, exist_ok=True)
        (d / "input.hex").write_text(data.hex() + "\n")
        (d / "repro.py").write_text(
            _SCRIPT.format(
                what=f"{kind} in {target}", name="repro.py", data=data.hex(), target=target, deadline=self.deadline
            )
        )
        desc = {
            "kind": kind,
            "target": target,
            "detail": detail,
            "bytes": len(data),
            "seed": self.seed,
            "command": self.command,
        }
        (d / "finding.json").write_text(json.dumps(desc, indent=2) + "\n")
        self.stats.findings.append({"kind": kind, "reason": detail[-200:], "dir": str(d), "signature": signature})


def _mutate_bytes(doc: bytes, rng: random.Random) -> bytes:
    b = bytearray(doc)
    for _ in range(rng.choice((1, 2, 8))):
        if b:
            b[rng.randrange(len(b))] = rng.randrange(256)
    return bytes(b)


def reply_frame(rng: random.Random) -> bytes:
    """An honest reply frame with random in-domain values (the mutators then break it)."""
    cls = rng.choice(list(REPLIES))
    layout = cls.DEF.reply if cls.DEF.layout_known else None
    if layout is None:
        return encode(cls(bytes(rng.randrange(256) for _ in range(rng.randrange(8)))))
    return encode(cls(*[_value(f, rng) for f in layout if f.const is None]))


def _value(f: FieldDef, rng: random.Random) -> Any:
    if f.is_group:
        return tuple(tuple(_value(g, rng) for g in f.fields if g.const is None) for _ in range(rng.choice((0, 1, 3))))
    if f.type in ("STRING", "XML"):
        return rng.choice(("", "x", "Ärger", "<map/>"))
    if f.type == "DOUBLE" and rng.random() < 0.3:
        return rng.choice((math.nan, math.inf, -math.inf, -0.0, 5e-324))
    v = _valid_scalar(f, rng)
    return tuple(_valid_scalar(f, rng) for _ in range(f.repeat)) if f.repeat else v
