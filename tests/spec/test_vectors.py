"""The codec and ``pltf decode``/``pltf encode`` against the language-neutral vectors of fixtures/vectors/.

The vectors were transcribed from the guide by fixtures/vectors/make_vectors.py (struct.pack, no project
imports), so they are an oracle independent of spec/telegrams.yaml: a failure here means the codec and the
transcription of the guide disagree, and one of them is wrong. Do not regenerate the vectors from the codec.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from pltf.cli.main import main as pltf
from pltf.spec import errors
from pltf.spec.codec import REPLIES, REQUESTS, decode_frame, encode
from pltf.spec.jsonio import fields_to_telegram, telegram_to_json

VECTORS = Path(__file__).resolve().parents[2] / "fixtures" / "vectors"
ERROR_NAMES = {
    "BadHeader",
    "FrameTooLarge",
    "Truncated",
    "TrailingBytes",
    "UnknownTelegram",
    "FieldOutOfRange",
    "LengthMismatch",
}
VALID_KEYS = {"name", "telegram", "id", "direction", "hex", "fields", "source"}
INVALID_KEYS = {"name", "direction", "hex", "error", "why"}


def _load(name: str) -> list[dict[str, Any]]:
    data = json.loads((VECTORS / name).read_text(encoding="ascii"))
    assert isinstance(data, list)
    return data


REQUEST_VECTORS = _load("requests.json")
REPLY_VECTORS = _load("replies.json")
VALID = REQUEST_VECTORS + REPLY_VECTORS
INVALID = _load("invalid.json")


def _ids(vectors: list[dict[str, Any]]) -> list[str]:
    return [v["name"] for v in vectors]


def _flag(direction: str) -> list[str]:
    return ["--reply"] if direction == "reply" else []


def _make_vectors_module() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_vectors", VECTORS / "make_vectors.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ------------------------------------------------------------------ the files themselves


def test_files_are_what_make_vectors_writes() -> None:
    mv = _make_vectors_module()
    built = mv.build()
    assert sorted(built) == sorted(["requests.json", "replies.json", "invalid.json"])
    for name, entries in built.items():
        assert (VECTORS / name).read_text(encoding="ascii") == mv.render(entries), (
            f"{name} is stale: run fixtures/vectors/make_vectors.py"
        )


def test_vector_format() -> None:
    names = [v["name"] for v in VALID + INVALID]
    assert len(names) == len(set(names)), "vector names must be unique across the three files"
    for v in REQUEST_VECTORS:
        assert v["direction"] == "request"
    for v in REPLY_VECTORS:
        assert v["direction"] == "reply"
    for v in VALID:
        assert set(v) == VALID_KEYS, v["name"]
        assert v["hex"] == v["hex"].lower() and bytes.fromhex(v["hex"]).hex() == v["hex"], v["name"]
        raw = bytes.fromhex(v["hex"])
        assert raw[:4] == b"\xff\x01\xfe\x02" and int.from_bytes(raw[4:8], "big") == len(raw) - 8, v["name"]
        assert raw[8] == v["id"], v["name"]
        assert isinstance(v["fields"], dict) and v["source"], v["name"]
    for v in INVALID:
        assert set(v) == INVALID_KEYS, v["name"]
        assert v["direction"] in ("request", "reply") and v["error"] in ERROR_NAMES and v["why"], v["name"]
        assert v["hex"] == v["hex"].lower(), v["name"]
    assert {v["error"] for v in INVALID} == ERROR_NAMES, "every error class has at least one invalid vector"


def test_the_seven_captures_are_included_verbatim() -> None:
    captured = {
        "ff01fe020000000100",
        "ff01fe02000000010e",
        "ff01fe02000000010d",
        "ff01fe02000000050f00000003",
        "ff01fe0200000009170000012c0000012c",
        "ff01fe020000000917fffffed4fffffed4",
        "ff01fe020000000d16000003e80000000000000000",
    }
    got = {v["hex"] for v in REQUEST_VECTORS if v["source"] == "field-evidence capture"}
    assert got == captured


@pytest.mark.parametrize(("direction", "tset"), [("request", REQUESTS), ("reply", REPLIES)])
def test_every_telegram_id_has_a_vector(direction: str, tset: Any) -> None:
    covered = {v["id"] for v in VALID if v["direction"] == direction}
    wanted = {cls.ID for cls in tset}
    assert wanted - covered == set(), f"{direction} ids without a vector"
    assert covered - wanted == set(), f"{direction} vectors for ids the codec does not know"


# ------------------------------------------------------------------ valid vectors: codec and CLI


@pytest.mark.parametrize("vector", VALID, ids=_ids(VALID))
def test_codec_decodes_and_reencodes(vector: dict[str, Any]) -> None:
    raw = bytes.fromhex(vector["hex"])
    telegram = decode_frame(raw, vector["direction"])
    as_json = telegram_to_json(telegram)
    assert (as_json["telegram"], as_json["id"]) == (vector["telegram"], vector["id"])
    assert as_json["fields"] == vector["fields"]
    assert encode(telegram) == raw


@pytest.mark.parametrize("vector", VALID, ids=_ids(VALID))
def test_codec_encodes_from_json_fields(vector: dict[str, Any]) -> None:
    """From the vector's JSON fields alone, as a stub's test builds a telegram."""
    telegram = fields_to_telegram(vector["direction"], vector["telegram"], vector["fields"])
    assert encode(telegram).hex() == vector["hex"]


@pytest.mark.parametrize("vector", VALID, ids=_ids(VALID))
def test_cli_decode_and_encode_agree(vector: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert pltf(["decode", vector["hex"], *_flag(vector["direction"])]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    lines = out.splitlines()
    assert len(lines) == 1
    printed = json.loads(lines[0])
    assert (printed["telegram"], printed["id"], printed["fields"]) == (
        vector["telegram"],
        vector["id"],
        vector["fields"],
    )

    assert pltf(["encode", vector["telegram"], json.dumps(vector["fields"]), *_flag(vector["direction"])]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    assert out.strip() == vector["hex"]


# ------------------------------------------------------------------ invalid vectors


@pytest.mark.parametrize("vector", INVALID, ids=_ids(INVALID))
def test_codec_refuses_invalid(vector: dict[str, Any]) -> None:
    expected = getattr(errors, vector["error"])
    with pytest.raises(errors.RemoteProtocolError) as info:
        decode_frame(bytes.fromhex(vector["hex"]), vector["direction"])
    assert type(info.value) is expected, f"{vector['name']}: {type(info.value).__name__}: {info.value}"


@pytest.mark.parametrize("vector", INVALID, ids=_ids(INVALID))
def test_cli_refuses_invalid(vector: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert pltf(["decode", vector["hex"], *_flag(vector["direction"])]) == 2
    _, err = capsys.readouterr()
    assert len(err.splitlines()) == 1, err
    assert "Traceback" not in err
