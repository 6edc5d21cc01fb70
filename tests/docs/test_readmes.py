"""No README links outside the repository (issue 31): every link of every README.md is a path to a file or
folder of the checkout, never a web address and never a path that climbs out (../shared/STYLE.md did)."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

from tests.docs.blocks import REPO

LINK = re.compile(r"\]\(([^)\s]+)\)")
CODE_PATH = re.compile(r"`(\.\./[^`\s]*)`")  # a path named in code, `../shared/STYLE.md`, is a link too
FENCE = re.compile(r"^```.*?^```", re.M | re.S)


def _readmes() -> list[str]:
    out = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard", "*README.md"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    return sorted(p for p in out.splitlines() if (REPO / p).is_file())


def _outside(target: str, here: Path, root: Path) -> bool:
    where = target.partition("#")[0]
    web = re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target) or target.startswith("//")
    return bool(web) or (bool(where) and not (here / where).resolve().is_relative_to(root.resolve()))


def _problems(readme: str, root: Path = REPO) -> list[str]:
    path = root / readme
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    problems = []
    for target in LINK.findall(text) + CODE_PATH.findall(text):
        where = target.partition("#")[0]
        if _outside(target, path.parent, root):
            problems.append(f"{readme}: links outside the repository: {target}")
        elif where and not (path.parent / where).exists():
            problems.append(f"{readme}: links to a path the repository does not have: {target}")
    return problems


def test_no_readme_links_outside_the_repository() -> None:
    readmes = _readmes()
    assert "README.md" in readmes and len(readmes) > 10
    problems = [p for r in readmes for p in _problems(r)]
    assert problems == []


def test_the_check_sees_a_link_out(tmp_path: Path) -> None:
    (tmp_path / "docs").mkdir()
    (tmp_path / "README.md").write_text("x\n")
    (tmp_path / "docs" / "README.md").write_text(
        "[style](../../shared/STYLE.md) [web](https://example.org/) [ok](../README.md) [gone](x.md)\n"
        "See `../../shared/STYLE.md`; `../README.md` is fine.\n"
    )
    assert _problems("docs/README.md", tmp_path) == [
        "docs/README.md: links outside the repository: ../../shared/STYLE.md",
        "docs/README.md: links outside the repository: https://example.org/",
        "docs/README.md: links to a path the repository does not have: x.md",
        "docs/README.md: links outside the repository: ../../shared/STYLE.md",
    ]
