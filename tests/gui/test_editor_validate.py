"""gui/validate.py over real HTTP (the gateway as a subprocess): the editors' check before sending answers every
body with a verdict of the project's own validator, never a traceback."""

from __future__ import annotations

import json
import urllib.error
import urllib.request
from typing import Any

import pytest

from tests.gui.conftest import REPO, Gateway


def post(gateway: Gateway, kind: str, body: bytes, headers: dict[str, str] | None = None) -> tuple[int, Any]:
    req = urllib.request.Request(f"{gateway.base}/api/validate?kind={kind}", data=body, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, e.read().decode()


@pytest.mark.parametrize(
    ("kind", "path"), [("map", "fixtures/maps/office.map"), ("roadmap", "fixtures/roadmaps/office.rm")]
)
def test_the_fixture_documents_are_valid(gateway: Gateway, kind: str, path: str) -> None:
    assert post(gateway, kind, (REPO / path).read_bytes()) == (200, {"ok": True})


@pytest.mark.parametrize(
    ("kind", "path", "line", "says"),
    [
        ("map", "missing_point.map", 6, "Element 'line': Missing child element(s)"),
        ("roadmap", "dangling_edge.rm", 7, "No match found for key-sequence ['nowhere']"),
        ("roadmap", "bad_number.rm", 6, "'1e3' is not a valid value"),
        ("map", "billion_laughs.map", None, "entity declarations are not allowed"),
        ("map", "wrong_root.map", None, "expected <map>"),
    ],
)
def test_an_invalid_document_gets_its_reason_and_line(
    gateway: Gateway, kind: str, path: str, line: int | None, says: str
) -> None:
    status, verdict = post(gateway, kind, (REPO / "fixtures" / "invalid" / path).read_bytes())
    assert status == 200 and verdict["ok"] is False, verdict
    assert says in verdict["message"] and "\n" not in verdict["message"]
    if line is not None:
        assert verdict["line"] == line


def test_garbage_an_oversized_body_an_unknown_kind_and_another_origin(gateway: Gateway) -> None:
    status, verdict = post(gateway, "map", b"\x00\xff<map")
    assert status == 200 and verdict["ok"] is False and "not well-formed" in verdict["message"]
    status, verdict = post(gateway, "map", b"<map>" + b" " * (17 * 1024 * 1024) + b"</map>")
    assert status == 200 and verdict == {
        "ok": False,
        "message": f"the document is over {16 * 1024 * 1024} bytes",
        "line": None,
    }
    assert post(gateway, "program", b"<program/>")[0] == 400
    assert post(gateway, "map", b"<map/>", {"Origin": "http://elsewhere.example"})[0] == 403
