"""The test vectors of ``fixtures/vectors/*.json`` as lines every generated vector runner reads.

Not every target language parses JSON with its standard library, so the runners read this line format:

    V <direction> <telegram> <hex> [<dump>]     a valid frame: decode, compare the dump, re-encode to <hex>
    E <direction> <vector-name> <hex> <Error>   an invalid frame: decoding must raise <Error>

``<hex>`` is ``-`` for no bytes; ``<dump>`` is ``model.dump`` of the vector's fields (the rest of the line).
Lines starting with ``#`` are comments. Run ``python -m pltf.stubgen.vectors [DIR] OUT`` to write it
(the fixture vectors, then ``sample_entries``: extra vectors made with ``pltf.spec.codec``).
"""

from __future__ import annotations

import dataclasses
import json
import random
import struct
import sys
from pathlib import Path
from typing import Any

from pltf.fixtures import DIR as FIXTURES_DIR
from pltf.spec import errors
from pltf.spec.codec import decode_frame, encode, frame, telegram_set
from pltf.spec.jsonio import telegram_to_json
from pltf.spec.model import load_telegrams
from pltf.stubgen.model import INT_BOUNDS, Field, Message, dump, messages

VECTOR_FILES = ("requests.json", "replies.json", "invalid.json")
DEFAULT_DIR = FIXTURES_DIR / "vectors"


def _entries(data: Any) -> list[dict[str, Any]]:
    if isinstance(data, dict):
        lists = [v for v in data.values() if isinstance(v, list)]
        if len(lists) != 1:
            raise ValueError("expected a list of vectors, or an object holding one")
        data = lists[0]
    return list(data)


def load(directory: Path = DEFAULT_DIR) -> list[dict[str, Any]]:
    out: list[dict[str, Any]] = []
    for name in VECTOR_FILES:
        path = directory / name
        if path.exists():
            out.extend(_entries(json.loads(path.read_text(encoding="utf-8"))))
    return out


def _word(text: str | None) -> str:
    return "-" if not text else "_".join(str(text).split())


def lines(entries: list[dict[str, Any]]) -> list[str]:
    by_name: dict[tuple[str, str], Message] = {(d, m.name): m for d in ("request", "reply") for m in messages(d)}
    for t in load_telegrams():
        for alias in t.aliases:
            for d in ("request", "reply"):
                if (d, t.name) in by_name:
                    by_name[(d, alias)] = by_name[(d, t.name)]
    out = []
    for e in entries:
        direction, hexstr = e["direction"], _word(e.get("hex", "").replace(" ", "").lower())
        if "error" in e:
            out.append(f"E {direction} {_word(e.get('name'))} {hexstr} {e['error']}")
            continue
        message = by_name[(direction, e["telegram"])]
        text = dump(message, e.get("fields") or {})
        out.append(f"V {direction} {message.name} {hexstr}" + (f" {text}" if text else ""))
    return out


_DOUBLES = (0.0, -0.0, 1.0, -2.5, 0.1, 1e300, -5e-324, 2.0**53 + 1, 3.141592653589793)
_TEXT = "".join(map(chr, range(256)))


def _sample(f: Field, rnd: random.Random) -> Any:
    if f.is_group:
        return [{g.name: _sample(g, rnd) for g in f.user_fields} for _ in range(rnd.randrange(4))]
    if f.repeat:
        return [_sample(_single(f), rnd) for _ in range(f.repeat)]
    if f.is_text:
        return "".join(rnd.choice(_TEXT) for _ in range(rnd.choice((0, 1, 5, 17))))
    if f.type == "DOUBLE":
        return rnd.choice(_DOUBLES)
    if f.allowed is not None:
        return rnd.choice(f.allowed)
    lo, hi = INT_BOUNDS[f.type]
    lo, hi = max(lo, f.min if f.min is not None else lo), min(hi, f.max if f.max is not None else hi)
    return rnd.choice((lo, hi, rnd.randint(lo, hi), min(max(0, lo), hi)))


def _single(f: Field) -> Field:
    return dataclasses.replace(f, repeat=0)


def _python_value(f: Field, v: Any) -> Any:
    if f.is_group:
        return tuple(tuple(_python_value(g, item[g.name]) for g in f.user_fields) for item in v)
    return tuple(v) if f.repeat else v


def _build(direction: str, m: Message, fields: dict[str, Any]) -> Any:
    # spec.jsonio.fields_to_telegram cannot build telegrams with a field called "name" (build()'s own
    # argument), so the class is called directly.
    cls = telegram_set(direction).by_name[m.name]  # type: ignore[arg-type]
    if m.opaque:
        return cls._make((bytes.fromhex(fields["payload"]),))  # type: ignore[attr-defined]
    return cls._make(_python_value(f, fields[f.name]) for f in m.user_fields)  # type: ignore[attr-defined]


def _expect_error(name: str, direction: str, data: bytes) -> dict[str, Any] | None:
    try:
        decode_frame(data, direction)  # type: ignore[arg-type]
    except errors.RemoteProtocolError as exc:
        return {"name": name, "direction": direction, "hex": data.hex(), "error": type(exc).__name__}
    return None


def sample_entries(seed: int = 9, per_telegram: int = 3) -> list[dict[str, Any]]:
    """Vectors made with the Python codec (``pltf.spec.codec``): a few valid frames of every telegram in both
    directions, and each of them broken (cut short, extended, a byte flipped) with the error it raises.
    They add coverage beside ``fixtures/vectors``; they are not an independent oracle."""
    rnd = random.Random(seed)
    valid, invalid = [], []
    for direction in ("request", "reply"):
        for m in messages(direction):
            for i in range(per_telegram):
                if m.opaque:
                    fields: dict[str, Any] = {"payload": rnd.randbytes(rnd.randrange(6)).hex()}
                else:
                    fields = {f.name: _sample(f, rnd) for f in m.user_fields}
                t = _build(direction, m, fields)
                data = encode(t)
                back = telegram_to_json(decode_frame(data, direction))
                valid.append(
                    {
                        "name": f"{m.name}-{i}",
                        "telegram": m.name,
                        "direction": direction,
                        "hex": data.hex(),
                        "fields": back["fields"],
                    }
                )
                body = data[8:]
                flip = bytearray(body)
                if len(flip) > 1:
                    k = rnd.randrange(1, len(flip))
                    flip[k] ^= rnd.choice((0x80, 0xFF, 0x01))
                for tag, broken in (
                    ("cut", data[:-1]),
                    ("extra", data + b"\x00"),
                    ("short", frame(body[:-1])),
                    ("long", frame(body + b"\x01")),
                    ("flip", frame(bytes(flip))),
                ):
                    entry = _expect_error(f"{m.name}-{i}-{tag}", direction, broken)
                    if entry is not None:
                        invalid.append(entry)
    for name, data in (
        ("bad-header", bytes.fromhex("ff01fe030000000100")),
        ("bad-first-byte", b"\x00"),
        ("empty-data", frame(b"")),
        ("unknown-id", frame(b"\x41")),
        ("too-large", struct.pack(">4sI", b"\xff\x01\xfe\x02", 16 * 1024 * 1024 + 1)),
        ("header-only", b"\xff\x01\xfe"),
    ):
        for direction in ("request", "reply"):
            entry = _expect_error(f"{name}-{direction}", direction, data)
            assert entry is not None, name
            invalid.append(entry)
    return valid + invalid


def write(out: Path, directory: Path = DEFAULT_DIR, samples: bool = False) -> int:
    entries = load(directory) + (sample_entries() if samples else [])
    out.write_text("".join(line + "\n" for line in lines(entries)), encoding="ascii")
    return len(entries)


def main(argv: list[str]) -> int:
    if len(argv) not in (1, 2):
        print("usage: python -m pltf.stubgen.vectors [VECTOR_DIR] OUT", file=sys.stderr)
        return 2
    directory = Path(argv[0]) if len(argv) == 2 else DEFAULT_DIR
    count = write(Path(argv[-1]), directory, samples=True)
    print(f"{count} vectors written to {argv[-1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
