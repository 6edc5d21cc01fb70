"""The fleet's matrix report (reports/matrix.py): which rows differ, which target is the odd one, how a difference
is named, and the HTML page in a real browser (chromium): the differing rows highlighted, a button that shows only
them. Plain data in, no target needed."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from pltf.conformance_tests.fleet import FleetTarget, TargetRun
from pltf.conformance_tests.reports import matrix

CHROMIUM = "/usr/bin/chromium"  # Debian's, as tests/gui drives it
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--no-first-run"]


def _case(case: str, verdict: str, errata: tuple[str, ...] = (), deviations: tuple[str, ...] = ()) -> dict[str, Any]:
    return {
        "id": case,
        "level": "MUST",
        "errata": list(errata),
        "verdict": verdict,
        "message": f"{verdict} because",
        "deviations": [{"erratum": d} for d in deviations],
    }


def _runs() -> tuple[list[FleetTarget], list[TargetRun]]:
    table = {
        "a": [_case("6.2/x", "PASS"), _case("5.9/p", "PASS", ("E-PAR-024",)), _case("6.3/q", "PASS")],
        "b": [_case("6.2/x", "PASS"), _case("5.9/p", "N/A", ("E-PAR-024",)), _case("6.3/q", "FAIL")],
        "c": [
            _case("6.2/x", "PASS"),
            _case("5.9/p", "PASS", ("E-PAR-024",)),
            _case("6.1/r", "NON-STRICT", (), ("E-WIRE-007",)),
        ],
    }
    targets = [FleetTarget(n, "127.0.0.1", 1000 + i) for i, n in enumerate(table)]
    runs = [
        TargetRun(n, t.address, 0, {"cases": cases, "counts": {"PASS": 2}}, "")
        for t, (n, cases) in zip(targets, table.items(), strict=True)
    ]
    return targets, runs


def test_rows_name_the_odd_target_and_the_documented_errata() -> None:
    rows = {r.case: r for r in matrix.rows(_runs()[1])}
    assert list(rows) == ["6.2/x", "5.9/p", "6.3/q", "6.1/r"]
    assert not rows["6.2/x"].differs and rows["6.2/x"].named() == []
    params = rows["5.9/p"]
    assert params.differs and params.odd() == ["b"]
    (named,) = params.named()
    assert named.startswith("E-PAR-024 (errata register, parameters.yaml") and "zoo/emulator_differences.yaml" in named
    assert rows["6.3/q"].cells["c"] is None and rows["6.3/q"].odd() == ["a", "b", "c"]  # no majority: all named
    assert rows["6.3/q"].named() == ["undocumented: the case cites no erratum"]
    assert rows["6.1/r"].named()[0].startswith("E-WIRE-007 (errata register, wire.yaml")  # from the cell's deviation


def test_the_json_matrix(tmp_path: Path) -> None:
    targets, runs = _runs()
    matrix.write_json("fleet.yaml", targets, runs, 1, str(tmp_path / "f.json"))
    data = json.loads((tmp_path / "f.json").read_text())
    assert (data["exit_code"], data["differences"], [t["name"] for t in data["targets"]]) == (1, 3, ["a", "b", "c"])
    row = next(r for r in data["matrix"] if r["case"] == "5.9/p")
    assert row["verdicts"] == {"a": "PASS", "b": "N/A", "c": "PASS"} and row["odd"] == ["b"]


def test_the_html_matrix_in_a_browser_highlights_and_filters_the_differences(tmp_path: Path) -> None:
    playwright_sync = pytest.importorskip("playwright.sync_api")
    if not Path(CHROMIUM).exists():
        pytest.fail(f"{CHROMIUM} is missing: `make chromium` installs Debian's chromium")
    targets, runs = _runs()
    page_file = tmp_path / "fleet.html"
    matrix.write_html("fleet.yaml", targets, runs, 1, str(page_file))
    with playwright_sync.sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page()
            page.goto(page_file.as_uri())
            rows = page.locator("table.m tr.r")
            assert rows.count() == 4
            highlighted = page.locator("table.m tr.r.d")
            assert highlighted.count() == 3
            assert "E-PAR-024" in highlighted.nth(0).inner_text()
            page.get_by_role("button", name="only differences").click()
            visible = [rows.nth(i).is_visible() for i in range(4)]
            assert visible == [False, True, True, True]
            page.get_by_role("button", name="all cases").click()
            assert all(rows.nth(i).is_visible() for i in range(4))
        finally:
            browser.close()
