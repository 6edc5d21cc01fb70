"""The case catalogue: every conformance case, its id, requirement, level, tier and flags.

Rules:
- A case is a plain function ``(ctx) -> None`` registered with ``@case(...)``. Its id is stable and names the
  guide section it checks (``6.3/CMD_SET_MODE/in-running``); the first path element is the section, so the
  reports can group by chapter. Ids never change meaning: a changed requirement gets a new id.
- ``requirement`` quotes the guide (or the errata decision that governs it). ``level`` is MUST unless given;
  when an erratum governs the case and no level is given, the erratum's level is the case's level.
- A case reports through exceptions (``outcome.py``); returning normally means PASS unless it recorded a
  deviation from an erratum's decision (``ctx.deviate``).
- Flags gate what a case may do to a real platform: ``moves_platform`` and ``switches_outputs`` need
  ``--allow-motion`` or ``--target-is-simulator``; ``destructive`` (CMD_EXIT, CMD_SHUTDOWN_HOST) needs
  ``--allow-shutdown`` and runs last.
"""

from __future__ import annotations

import enum
import fnmatch
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from pltf.spec.errata import load_errata


class Level(enum.StrEnum):
    MUST = "MUST"
    SHOULD = "SHOULD"
    MAY = "MAY"


class Tier(enum.IntEnum):
    SMOKE = 0
    STANDARD = 1
    EXHAUSTIVE = 2


class Verdict(enum.StrEnum):
    PASS = "PASS"
    FAIL = "FAIL"  # a MUST requirement is broken
    NON_STRICT = "NON-STRICT"  # a SHOULD requirement is broken, or an accepted alternative reading is followed
    NA = "N/A"  # an optional (MAY) feature the target lacks or declares absent
    INCONCLUSIVE = "INCONCLUSIVE"  # re-runs disagreed or the observation stayed within the noise
    ERROR = "ERROR"  # the harness itself failed
    SKIPPED = "SKIPPED"  # not run: the safety gate (or an unmet prerequisite of the run) held it back


# Guide section titles for the reports (chapter -> sections).
SECTIONS: dict[str, str] = {
    "4.2": "Operation (state chart)",
    "4.3": "Motion modes",
    "4.5": "Python task interpreter",
    "5.9": "Platform parameters",
    "6.1": "Socket API overview (ports, replies)",
    "6.2": "Message format",
    "6.3": "Commands",
    "6.4": "Reply telegrams",
    "6.5": "XML documents",
}

ID_PATTERN = re.compile(r"^(?P<section>\d\.\d)/[A-Za-z0-9_.-]+(/[A-Za-z0-9_.-]+)*$")


@dataclass(frozen=True)
class Case:
    id: str
    func: Callable[[Any], None]
    requirement: str
    level: Level
    tier: Tier
    group: str
    errata: tuple[str, ...] = ()
    moves_platform: bool = False
    switches_outputs: bool = False
    destructive: bool = False
    abuse: bool = False  # sends malformed input: the runner checks liveness afterwards
    timing: bool = False  # depends on timing: a failure is re-run to tell a flake from a failure
    telegrams: tuple[str, ...] = field(default=())  # the telegrams whose requirement this case checks

    @property
    def section(self) -> str:
        return self.id.split("/", 1)[0]

    @property
    def chapter(self) -> str:
        return self.section.split(".", 1)[0]

    @property
    def gated(self) -> bool:
        return self.moves_platform or self.switches_outputs

    @property
    def doc(self) -> str:
        return (self.func.__doc__ or "").strip()


REGISTRY: dict[str, Case] = {}


def case(
    case_id: str,
    *,
    requirement: str,
    tier: Tier = Tier.STANDARD,
    level: Level | str | None = None,
    errata: Iterable[str] = (),
    group: str | None = None,
    moves_platform: bool = False,
    switches_outputs: bool = False,
    destructive: bool = False,
    abuse: bool = False,
    timing: bool = False,
    telegrams: Iterable[str] = (),
) -> Callable[[Callable[[Any], None]], Callable[[Any], None]]:
    """Register a case function under ``case_id`` (see the module rules)."""

    def register(func: Callable[[Any], None]) -> Callable[[Any], None]:
        add(
            case_id,
            func,
            requirement=requirement,
            tier=tier,
            level=level,
            errata=errata,
            group=group,
            moves_platform=moves_platform,
            switches_outputs=switches_outputs,
            destructive=destructive,
            abuse=abuse,
            timing=timing,
            telegrams=telegrams,
        )
        return func

    return register


def add(case_id: str, func: Callable[[Any], None], **kw: Any) -> Case:
    """Register one case (``@case`` for functions, called directly for generated families)."""
    if not ID_PATTERN.match(case_id):
        raise ValueError(f"case id {case_id!r} does not start with a guide section (e.g. 6.3/CMD_X/what)")
    if case_id in REGISTRY:
        raise ValueError(f"duplicate case id {case_id}")
    errata = tuple(kw.pop("errata", ()))
    known = load_errata()
    for eid in errata:
        if eid not in known:
            raise ValueError(f"{case_id}: unknown erratum {eid}")
    level = kw.pop("level", None)
    if level is None:
        level = known[errata[0]].level if errata else Level.MUST
    group = kw.pop("group", None) or func.__module__.rsplit(".", 1)[-1]
    c = Case(
        id=case_id,
        func=func,
        level=Level(level),
        tier=Tier(kw.pop("tier", Tier.STANDARD)),
        group=group,
        errata=errata,
        telegrams=tuple(kw.pop("telegrams", ())),
        **kw,
    )
    REGISTRY[case_id] = c
    return c


def load_all() -> dict[str, Case]:
    """Import every case module (registration happens at import) and return the registry."""
    from pltf.conformance_tests import cases  # noqa: F401  (imports the case modules)

    return REGISTRY


def matches(c: Case, expr: str) -> bool:
    """``-k`` selection: ``and``/``or``/``not`` over substrings or globs of the id, group, level and flags."""
    words = {c.id.lower(), c.group.lower(), c.level.value.lower(), c.tier.name.lower()}
    for flag in ("moves_platform", "switches_outputs", "destructive", "abuse", "timing"):
        if getattr(c, flag):
            words.add(flag)
    words.update(t.lower() for t in c.telegrams)

    def hit(term: str) -> bool:
        term = term.lower()
        if any(ch in term for ch in "*?["):
            return any(fnmatch.fnmatchcase(w, term) for w in words)
        return any(term in w for w in words)

    tokens = re.findall(r"\(|\)|[^\s()]+", expr)
    py: list[str] = []
    names: dict[str, bool] = {}
    for tok in tokens:
        if tok.lower() in ("and", "or", "not") or tok in "()":
            py.append(tok.lower())
        else:
            key = f"_t{len(names)}"
            names[key] = hit(tok)
            py.append(key)
    try:
        return bool(eval(" ".join(py), {"__builtins__": {}}, names))  # only our own tokens
    except SyntaxError:
        raise ValueError(f"bad -k expression {expr!r}") from None


def select(cases: Iterable[Case], *, tier: Tier = Tier.STANDARD, keyword: str | None = None) -> list[Case]:
    """The cases of ``tier`` and below that match ``keyword``, in run order: by group (cases.GROUP_ORDER), then
    as registered; destructive ones last."""
    from pltf.conformance_tests.cases import GROUP_ORDER

    rank = {g: i for i, g in enumerate(GROUP_ORDER)}
    chosen = [c for c in cases if c.tier <= tier and (keyword is None or matches(c, keyword))]
    return sorted(chosen, key=lambda c: (c.destructive, rank.get(c.group, len(rank))))  # stable otherwise
