"""The language-neutral vectors of fixtures/vectors (the independent oracle), for the proxy's tests."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

VECTORS = Path(__file__).resolve().parents[2] / "fixtures" / "vectors"


def load(name: str) -> list[dict[str, Any]]:
    data = json.loads((VECTORS / name).read_text(encoding="ascii"))
    assert isinstance(data, list)
    return data


REQUESTS = load("requests.json")
REPLIES = load("replies.json")
VALID = REQUESTS + REPLIES
INVALID = load("invalid.json")


def whole_frame(v: dict[str, Any]) -> bool:
    """The vector is exactly one frame with a good header and length (its error is inside the telegram)."""
    data = bytes.fromhex(v["hex"])
    return (
        len(data) >= 8
        and data[:4] == b"\xff\x01\xfe\x02"
        and int.from_bytes(data[4:8], "big") <= 16 << 20
        and len(data) == 8 + int.from_bytes(data[4:8], "big")
    )


def stream_error(v: dict[str, Any]) -> str:
    """The error a stream reader reports for the vector's bytes followed by the end of the stream
    (fixtures/vectors/README.md: ``trailing_bytes_after_frame`` reads as a frame, then a truncated one)."""
    return "Truncated" if v["name"] == "trailing_bytes_after_frame" else str(v["error"])
