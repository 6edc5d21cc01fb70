"""Every case can fail: for each case, a mutant derived from what it checks, run until one kills it.

``python -m pltf.conformance_tests.mutants.matrix [-k EXPR]`` prints, per case, the first mutant that kills it.

Rules:
- Candidates come from the case itself: an explicit entry of ``EXPLICIT`` for cases whose requirement a generic
  fault cannot reach (framing, ports, parsing), a flipped state chart cell for a "not allowed" cell, then for each
  telegram the case names: a reply cut short (GET_*), the command dropped, the command answered.
- Killed means FAIL or NON-STRICT, or N/A for a MAY case (that is how a MAY requirement fails). Every mutant runs on
  a fresh reference server, so no case is judged on state another mutant left behind.
- Cases the reference server itself cannot pass are listed apart, each with its reason (``NOT_ON_REFERENCE``):
  N/A there, they can neither pass nor be shown to fail against it. Destructive cases run too: every mutant's
  server is a throw-away one.
"""

from __future__ import annotations

import argparse
import fnmatch
import sys
import time
from collections.abc import Callable, Mapping

from pltf.conformance_tests import chart
from pltf.conformance_tests.catalogue import Case, Level, Tier, Verdict, load_all, select
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.mutants import catalogue as mc
from pltf.conformance_tests.mutants.catalogue import Mutant
from pltf.conformance_tests.mutants.run import Bench
from pltf.conformance_tests.runner import CaseResult
from pltf.spec.codec import REQUESTS

# Case id -> why the reference server cannot pass it (N/A there). Empty: with its fake hardware (CAN boards with
# traffic, IO outputs, ultrasonic board, head drive) and its task interpreter every standard case passes on it,
# the CAN, digital-out, ultrasonic, head-drive and program cases included. It only shrinks; an entry that passes
# on the reference server is stale and fails tests/conformance_tests/test_reference.py.
NOT_ON_REFERENCE: Mapping[str, str] = {}


def _wire(name: str, factory: Callable[[], object]) -> Mutant:
    return Mutant(name, name, "", wire=factory)


def _patch(name: str) -> Mutant:
    return Mutant(name, name, "", patch=name)


EXPLICIT: dict[str, list[Mutant]] = {
    "6.2/framing/split-*": [_wire("split-frames-lost", mc.DropSplitFrames)],
    "6.2/framing/slow-sender": [_wire("split-frames-lost", mc.DropSplitFrames)],
    "6.2/framing/coalesced": [_wire("coalesced-frames-lost", mc.FirstFrameOnly)],
    "6.2/framing/no-header": [_wire("bad-header-skipped", mc.SkipMalformed)],
    "6.2/framing/bad-header": [_wire("bad-header-skipped", mc.SkipMalformed)],
    "6.2/framing/huge-length": [_wire("huge-length-waits", mc.WaitOnHugeLength)],
    "6.2/framing/half-close-partial": [_wire("half-close-ignored", mc.IgnoreHalfClose)],
    "6.2/framing/half-close-complete": [_wire("half-close-drops-replies", mc.CloseOnHalfClose)],
    "6.2/framing/*": [_wire("undecodable-ignored", mc.IgnoreUndecodable)],
    "6.3/CMD_SET_MODE/out-of-range-changes-nothing": [_wire("undecodable-ignored", mc.IgnoreUndecodable)],
    "6.1/ports/both-serve": [_wire("port-b-closed", lambda: mc.ClosePort(1))],
    "6.1/ports/second-client-turned-away": [_wire("second-client-kept", mc.KeepSecondClient)],
    "6.1/ports/reconnect": [_wire("no-reconnect", mc.RefuseReconnect)],
    "6.1/ports/abuse-leaves-other-port": [_wire("abuse-closes-all", mc.CloseAllOnMalformed)],
    "6.1/replies/only-on-request": [_wire("commands-acknowledged", mc.AckCommands)],
    "6.3/CMD_SET_PLTF_PARAM/malformed-refused": [_patch("parameter_text_lenient")],
    "6.3/CMD_SET_PLTF_PARAM/boolean-spellings": [_patch("parameter_text_lenient")],
    "6.3/CMD_SET_PLTF_PARAM/out-of-range-refused": [_patch("parameter_range_unchecked")],
    "6.3/CMD_SET_*/invalid-refused": [_patch("documents_unvalidated")],
    "6.3/CMD_SAVE_*/load-round-trip": [_patch("save_does_nothing")],
    "4.3/MODE_MOTION_VEL/watchdog": [_patch("no_watchdog")],
    "4.3/*/*-ignored": [_patch("moves_in_every_mode")],
    "6.3/CMD_STOP/halts-motion": [_patch("stop_keeps_command")],
    "6.3/CMD_EXIT/shuts-down": [_wire("exit-ignored", lambda: mc.DropRequest("CMD_EXIT"))],
    "6.3/CMD_MOVE_*/only-in-running": [],  # filled in by candidates(): the move allowed in Ready
}


def _chart_cell(case: Case) -> list[Mutant]:
    parts = case.id.split("/")
    if len(parts) != 3 or not parts[2].startswith("in-") or parts[1] not in chart.CHART_COMMANDS:
        return []
    command, state = parts[1], St(parts[2][3:])
    if chart.allowed(state, command):
        return [_wire(f"drop-{command}", lambda: mc.DropRequest(command))]
    return [_patch(f"allow:{command}:{state.value}")]


def candidates(case: Case) -> list[Mutant]:
    out: list[Mutant] = []
    for pattern, mutants in EXPLICIT.items():
        if fnmatch.fnmatchcase(case.id, pattern):
            out += mutants
    if fnmatch.fnmatchcase(case.id, "6.3/CMD_MOVE_*/only-in-running"):
        out.append(_patch(f"allow:{case.id.split('/')[1]}:ready"))
    out += _chart_cell(case)
    for name in case.telegrams:
        if REQUESTS[name].DEF.answered:
            out.append(_wire(f"short-reply-{name}", lambda n=name: mc.corrupt_reply(n)))  # type: ignore[misc]
        else:
            out.append(_wire(f"drop-{name}", lambda n=name: mc.DropRequest(n)))  # type: ignore[misc]
            out.append(_wire(f"answer-{name}", lambda n=name: mc.AnswerCommand(n)))  # type: ignore[misc]
    out.append(_wire("short-reply-CMD_GET_STATUS", lambda: mc.corrupt_reply("CMD_GET_STATUS")))
    return list({m.id: m for m in out}.values())


def killed(case: Case, result: CaseResult) -> bool:
    if result.verdict in (Verdict.FAIL, Verdict.NON_STRICT):
        return True
    return case.level is Level.MAY and result.verdict is Verdict.NA


def find_killer(bench: Bench, case: Case) -> tuple[Mutant | None, CaseResult | None]:
    last = None
    for m in candidates(case):
        results = bench.run(m, [case])
        if not results:  # the run stopped before the case (harness error): not a verdict
            continue
        last = results[0]
        if killed(case, last):
            return m, last
    return None, last


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m pltf.conformance_tests.mutants.matrix", description=__doc__)
    p.add_argument("-k", dest="keyword")
    p.add_argument("--time-scale", type=float, default=10.0)
    args = p.parse_args(argv)
    bench = Bench(args.time_scale)
    cases = [
        c for c in select(load_all().values(), tier=Tier.STANDARD, keyword=args.keyword) if c.id not in NOT_ON_REFERENCE
    ]
    survivors = 0
    for c in cases:
        t0 = time.monotonic()
        m, r = find_killer(bench, c)
        if m is None:
            survivors += 1
        verdict = r.verdict if r is not None else "-"
        print(
            f"{'killed  ' if m else 'SURVIVED'} {c.id:58} by {m.id if m else '-':40} {verdict:11} "
            f"({time.monotonic() - t0:.1f} s)",
            flush=True,
        )
    return 1 if survivors else 0


if __name__ == "__main__":
    sys.exit(main())
