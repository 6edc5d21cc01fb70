"""Run cases against mutants: ``python -m pltf.conformance_tests.mutants.run [--all-cases] [MUTANT ...]``.

``Bench`` holds one reference server with a frame proxy in front (the wire mutants are swapped in and out of the
proxy) and starts a patched server per model mutant. ``kill`` runs a mutant's killer case (or any cases) and
returns the results; a mutant is killed when its killer's verdict is FAIL, or NON-STRICT for a SHOULD
requirement.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterable, Iterator
from contextlib import contextmanager

from pltf.conformance_tests.catalogue import Case, Tier, Verdict, load_all, select
from pltf.conformance_tests.mutants.catalogue import MUTANTS, Mutant
from pltf.conformance_tests.mutants.proxy import FrameProxy
from pltf.conformance_tests.runner import CaseResult, Runner
from pltf.conformance_tests.target import Config
from pltf.harness import launch

KILLED = (Verdict.FAIL, Verdict.NON_STRICT)


def config_for(ports: list[int], time_scale: float) -> Config:
    return Config(
        "127.0.0.1",
        ports[0],
        ports[1],
        time_scale=time_scale,
        simulator=True,
        allow_shutdown=True,
        reruns=0,
        reply_timeout=1.5,
        connect_window=1.5,
    )


class Bench:
    """Starts a fresh reference server for every target: a mutant must not inherit the state another one left
    (a corrupted pose, a parameter). Wire mutants get a frame proxy in front; model mutants a patched server."""

    def __init__(self, time_scale: float = 10.0) -> None:
        self.time_scale = time_scale

    def __enter__(self) -> Bench:
        return self

    def __exit__(self, *exc: object) -> None:
        pass

    @contextmanager
    def target(self, mutant: Mutant | None, *, proxied: bool = True) -> Iterator[list[int]]:
        """The ports of the mutant (a faithful proxy in front of the reference server when None)."""
        patch = mutant.patch if mutant is not None else None
        with launch.reference(time_scale=self.time_scale, mutant=patch) as server:
            if patch is not None or not proxied:
                yield list(server.ports)
                return
            with FrameProxy("127.0.0.1", server.ports, mutant.make() if mutant is not None else None) as proxy:
                yield proxy.ports

    def run(self, mutant: Mutant | None, cases: Iterable[Case]) -> list[CaseResult]:
        with self.target(mutant) as ports:
            return Runner(config_for(ports, self.time_scale), list(cases)).run().results


def killer_case(mutant: Mutant) -> Case:
    return load_all()[mutant.killer]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m pltf.conformance_tests.mutants.run", description=__doc__)
    p.add_argument("mutants", nargs="*", help="mutant ids (default: all)")
    p.add_argument("--all-cases", action="store_true", help="run the whole standard tier against each mutant")
    p.add_argument("--time-scale", type=float, default=10.0)
    args = p.parse_args(argv)
    chosen = [m for m in MUTANTS if not args.mutants or m.id in args.mutants]
    survivors = 0
    with Bench(args.time_scale) as bench:
        for m in chosen:
            t0 = time.monotonic()
            cases = select(load_all().values(), tier=Tier.STANDARD) if args.all_cases else [killer_case(m)]
            results = bench.run(m, cases)
            killer = next(r for r in results if r.case.id == m.killer)
            failing = [r.case.id for r in results if r.verdict in KILLED]
            ok = killer.verdict in KILLED
            survivors += not ok
            print(
                f"{'killed  ' if ok else 'SURVIVED'} {m.id:32} {killer.verdict:11} {m.killer}  "
                f"({time.monotonic() - t0:.1f} s{f', {len(failing)} cases fail' if args.all_cases else ''})"
            )
            print(f"         {killer.message.splitlines()[0][:150] if killer.message else ''}")
    return 1 if survivors else 0


if __name__ == "__main__":
    sys.exit(main())
