"""The site's generators and checkers (docs/gen/): the architecture page follows the import-linter contract, the
CLI reference follows the parser, links to repository files are checked, and the link checker finds what is
broken in a built site. Each is run as make docs runs it, on real files."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path
from types import ModuleType, SimpleNamespace

import pytest

from tests.docs.blocks import REPO


def _module(name: str) -> ModuleType:
    """A script of docs/gen (no package: mkdocs loads the hooks by their path, as this does)."""
    spec = importlib.util.spec_from_file_location(f"docs_gen_{name}", REPO / "docs" / "gen" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


architecture = _module("architecture")
cli_reference = _module("cli_reference")
linkcheck = _module("linkcheck")
repo_links = _module("repo_links")


def _gen(script: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(REPO / "docs" / "gen" / script), *args], capture_output=True, text=True, check=False
    )


# ---- architecture.py
def test_the_architecture_page_is_current() -> None:
    proc = _gen("architecture.py", "--check")
    assert proc.returncode == 0, proc.stderr


def test_a_changed_contract_makes_the_page_stale(tmp_path: Path) -> None:
    text = (REPO / "pyproject.toml").read_text(encoding="utf-8")
    moved = text.replace('    "pltf.cli",\n', '    "pltf.cli | pltf.stubgen",\n', 1)
    moved = moved.replace(' | pltf.zoo | pltf.stubgen",', ' | pltf.zoo",', 1)
    assert moved != text
    (tmp_path / "pyproject.toml").write_text(moved, encoding="utf-8")
    page = (REPO / "docs" / "architecture.md").read_text(encoding="utf-8")
    contract = architecture.load(tmp_path / "pyproject.toml")
    assert architecture.updated(page, contract) != page
    assert contract.layers[0] == ("pltf.cli", "pltf.stubgen")


def test_every_part_of_the_contract_is_described_and_its_folder_exists() -> None:
    contract = architecture.load()
    packages = [p for row in contract.layers for p in row]
    assert sorted(packages) == sorted(architecture.PARTS)
    for folder, _ in architecture.PARTS.values():
        assert (REPO / folder).is_dir(), folder
    assert all(e.reason for e in contract.exceptions), "an ignore_imports entry without a comment above it"


def test_the_diagram_draws_each_layer_and_each_exception() -> None:
    contract = architecture.load()
    diagram = architecture.mermaid(contract)
    assert diagram.count("subgraph") == len(contract.layers)
    assert "spec --> " not in diagram and "L0 --> L1" in diagram
    assert "gui -.-> proxy" in diagram  # gui.recorded imports proxy.session: a listed exception
    assert "harness -.->" not in diagram  # the launcher imports nothing above it (none listed)
    assert architecture.may_import(contract, "pltf.gui") == ["spec"]  # the forbidden contract narrows the layers
    picture = architecture.svg(contract)
    assert picture.count('class="band"') == len(contract.layers)
    assert all(f'class="name">{p.removeprefix("pltf.")}<' in picture for row in contract.layers for p in row)
    pairs = {(architecture._package(e.importer), architecture._package(e.imported)) for e in contract.exceptions}
    assert picture.count('class="exception"') == len(pairs)


# ---- cli_reference.py
def test_the_cli_reference_has_every_command_and_option() -> None:
    page = cli_reference.render()
    for name, (parser, _) in cli_reference._parsers().items():
        assert f"## pltf {name}\n" in page
        for action in parser._actions:
            for flag in action.option_strings:
                if flag not in ("-h", "--help"):
                    assert f"`{flag}`" in page, (name, flag)
    assert "| 1 | a case failed" in page  # conform's exit statuses, from its epilog


def test_a_tool_page_gets_its_command_and_an_unknown_command_is_a_warning(caplog: pytest.LogCaptureFixture) -> None:
    page = SimpleNamespace(file=SimpleNamespace(src_uri="tools/x.md"))
    out = cli_reference.on_page_markdown("# x\n\n<!-- pltf-cli replay -->\n", page, None, None)
    assert "`--second-port`" in out and "| 1 | a reply differs" in out
    kept = cli_reference.on_page_markdown("<!-- pltf-cli nope -->\n", page, None, None)
    assert kept == "<!-- pltf-cli nope -->\n"
    assert "pltf has no such command" in caplog.text


# ---- repo_links.py
def test_links_to_repository_files(caplog: pytest.LogCaptureFixture) -> None:
    docs = REPO / "docs"
    page = SimpleNamespace(file=SimpleNamespace(src_uri="tools/x.md"))
    config = {"docs_dir": str(docs)}
    text = (
        "[zoo](../../zoo/README.md) [sec](../../zoo/README.md#zoo) [in](../protocol.md) [web](https://x.y/) "
        "[gone](../../zoo/NOPE.md) [out](../../../etc/passwd)\n```sh\n[code](../../zoo/NOPE.md)\n```\n"
    )
    out = repo_links.on_page_markdown(text, page, config, None)
    assert f"({repo_links.MARK}zoo/README.md)" in out and f"({repo_links.MARK}zoo/README.md#zoo)" in out
    assert "(../protocol.md)" in out and "(https://x.y/)" in out
    assert "[code](../../zoo/NOPE.md)" in out  # code blocks are never rewritten
    assert "a file the repository does not have: ../../zoo/NOPE.md" in caplog.text
    assert "links outside the repository: ../../../etc/passwd" in caplog.text
    assert caplog.text.count("WARNING") == 2
    html = f'<a href="{repo_links.MARK}zoo/README.md#zoo">'
    site_page = SimpleNamespace(file=SimpleNamespace(dest_uri="tools/x/index.html"))
    built = repo_links.on_page_content(html, site_page, {"site_dir": str(REPO / "site")}, None)
    assert built == '<a href="../../../zoo/README.md#zoo">'


# ---- linkcheck.py
def _site(tmp_path: Path, body: str) -> Path:
    site = tmp_path / "site"
    (site / "a").mkdir(parents=True)
    (site / "index.html").write_text('<h1 id="top">x</h1><a href="a/">a</a>', encoding="utf-8")
    (site / "a" / "index.html").write_text(body, encoding="utf-8")
    (tmp_path / "file.md").write_text("x", encoding="utf-8")
    return site


def test_linkcheck_passes_a_sound_site(tmp_path: Path) -> None:
    site = _site(tmp_path, '<a href="../#top">up</a> <a href="../../file.md">repo</a> <a href="https://x.y/">w</a>')
    broken, external = linkcheck.check(site)
    assert broken == [] and external == ["https://x.y/"]
    assert linkcheck.main([str(site)]) == 0


def test_linkcheck_names_each_broken_link(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    site = _site(tmp_path, '<a href="../b/">b</a> <a href="../#nowhere">x</a> <img src="../../gone.png">')
    assert linkcheck.main([str(site)]) == 1
    err = capsys.readouterr().err
    assert "a/index.html: broken link '../b/': no such file" in err
    assert "a/index.html: broken link '../#nowhere': index.html has no #nowhere" in err
    assert "broken link '../../gone.png'" in err
    assert linkcheck.main([str(tmp_path / "nothing")]) == 2
