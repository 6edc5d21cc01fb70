"""Compile the spec's layouts into fast decode/encode functions (once, at import).

Rules:
- No per-telegram code is written by hand: each layout is turned into Python source that is exec'ed once
  (the technique of ``dataclasses`` and ``attrs``), with one precompiled ``struct.Struct`` per run of
  fixed-size fields and per fixed-size group item.
- Decode functions take the telegram's data (identifier at offset 0) and raise only RemoteProtocolError
  subclasses; encode functions take a telegram and raise only LocalProtocolError subclasses.
- Every count and length is checked against the bytes that remain before anything is allocated.
"""

from __future__ import annotations

import itertools
import struct
from collections.abc import Callable
from typing import Any

from pltf.spec import errors
from pltf.spec.model import Direction, FieldDef, TelegramDef, load_enums
from pltf.spec.telegram import Telegram, make_item_class, make_telegram_class, user_fields

# guide 6.2 (type table) and field evidence: BYTE u8, INT i32 two's complement MSB first, DOUBLE IEEE-754
# big-endian, BOOL 1 byte 0/1, INT16 i16 (status scan points).
WIRE: dict[str, tuple[str, int]] = {
    "BYTE": ("B", 1),
    "BOOL": ("B", 1),
    "INT16": ("h", 2),
    "INT": ("i", 4),
    "DOUBLE": ("d", 8),
}
LENGTH = struct.Struct(">i")  # STRING/XML length and group counts are INT (signed: a negative one is refused)

Decoder = Callable[[bytes], Telegram]
Encoder = Callable[[Telegram], bytes]


def fixed_size(f: FieldDef) -> int | None:
    """Bytes on the wire of a field, or None when it depends on the data."""
    if f.type in WIRE:
        return WIRE[f.type][1] * (f.repeat or 1)
    return None


def distance_from_end(fields: tuple[FieldDef, ...], name: str) -> int | None:
    """Bytes from the first byte of field ``name`` to the end of the telegram, when that field and every one
    after it have fixed sizes (None otherwise): the CMD_GET_STATUS timestamp sits at a fixed distance from the
    end however long the scan before it is."""
    names = [f.name for f in fields]
    sizes = [fixed_size(f) for f in fields[names.index(name) :]]
    return None if None in sizes else sum(n for n in sizes if n is not None)


def min_size(f: FieldDef) -> int:
    """The fewest bytes a field can take (for count checks before allocation)."""
    size = fixed_size(f)
    if size is not None:
        return size
    return LENGTH.size  # a string's or group's length/count field


def allowed_values(f: FieldDef) -> frozenset[int] | None:
    if f.enum is not None:
        return frozenset(load_enums()[f.enum].values.values())
    if f.type == "BOOL":
        return frozenset((0, 1))
    return None


def value_range(f: FieldDef) -> tuple[int, int] | None:
    if f.min is None and f.max is None:
        return None
    lo = f.min if f.min is not None else -(2**63)
    hi = f.max if f.max is not None else 2**63
    return lo, hi


def check_value(f: FieldDef, value: Any, where: str) -> str | None:
    """Slow, precise validation of one user value; the message of the first problem, or None."""
    name = f"{where}.{f.name}"
    if f.is_group:
        return _check_group(f, value, name)
    if f.type in ("STRING", "XML"):
        return _check_text(value, name)
    values = value if f.repeat else (value,)
    if f.repeat and (not isinstance(value, (tuple, list)) or len(value) != f.repeat):
        return f"{name}: expected {f.repeat} values"
    for v in values:
        msg = _check_number(f, v, name)
        if msg:
            return msg
    return None


def _check_group(f: FieldDef, value: Any, name: str) -> str | None:
    if not isinstance(value, (tuple, list)):
        return f"{name}: expected a sequence of {f.item}, got {type(value).__name__}"
    sub = user_fields(f.fields)
    for i, item in enumerate(value):
        if not isinstance(item, (tuple, list)) or len(item) != len(sub):
            return f"{name}[{i}]: expected {len(sub)} values ({', '.join(g.name for g in sub)})"
        for g, v in zip(sub, item, strict=True):
            msg = check_value(g, v, f"{name}[{i}]")
            if msg:
                return msg
    return None


def _check_text(value: Any, name: str) -> str | None:
    if isinstance(value, (bytes, bytearray)):
        return None
    if not isinstance(value, str):
        return f"{name}: expected str, got {type(value).__name__}"
    try:
        value.encode("latin-1")
    except UnicodeEncodeError as exc:
        return f"{name}: not encodable as Latin-1 (erratum E-WIRE-003): {exc.reason} at {exc.start}"
    return None


def _check_number(f: FieldDef, v: Any, name: str) -> str | None:
    char = WIRE[f.type][0]
    if char == "d":
        return (
            None if isinstance(v, (int, float)) and not isinstance(v, bool) else f"{name}: expected a number, got {v!r}"
        )
    if isinstance(v, bool) or not isinstance(v, int):
        return f"{name}: expected an integer, got {v!r}"
    try:
        struct.pack(">" + char, v)
    except struct.error:
        return f"{name}: {v} does not fit {f.type}"
    allowed, rng = allowed_values(f), value_range(f)
    if allowed is not None and v not in allowed:
        return f"{name}: {v} is not a valid {f.enum or f.type} value"
    if rng is not None and not rng[0] <= v <= rng[1]:
        return f"{name}: {v} outside {rng[0]}..{rng[1]}"
    return None


class _Source:
    """Accumulates generated source and the constants it refers to."""

    def __init__(self, where: str) -> None:
        self.where = where
        self.lines: list[str] = []
        self.ns: dict[str, Any] = {
            "errors": errors,
            "_LEN": LENGTH,
            "_tuple": tuple,
            "_map": map,
            "_range": range,
            "_bytes": bytes,
            "_isinstance": isinstance,
            "_starmap": itertools.starmap,
        }
        self._n = 0

    def name(self, prefix: str) -> str:
        self._n += 1
        return f"_{prefix}{self._n}"

    def const(self, prefix: str, value: Any) -> str:
        key = self.name(prefix)
        self.ns[key] = value
        return key

    def emit(self, depth: int, line: str) -> None:
        self.lines.append("    " * depth + line)

    def compile(self, func: str) -> Any:
        code = "\n".join(self.lines)
        exec(compile(code, f"<spec:{self.where}>", "exec"), self.ns)
        return self.ns[func]


def _runs(fields: tuple[FieldDef, ...]) -> list[list[FieldDef] | FieldDef]:
    """Split a layout into runs of consecutive fixed-size fields and single variable-size fields."""
    out: list[list[FieldDef] | FieldDef] = []
    for f in fields:
        if fixed_size(f) is not None:
            if out and isinstance(out[-1], list):
                out[-1].append(f)
            else:
                out.append([f])
        else:
            out.append(f)
    return out


def _struct_of(run: list[FieldDef]) -> struct.Struct:
    return struct.Struct(">" + "".join(f"{f.repeat or ''}{WIRE[f.type][0]}" for f in run))


def _emit_checks(src: _Source, depth: int, f: FieldDef, var: str, where: str) -> None:
    allowed, rng = allowed_values(f), value_range(f)
    label = f"{where}.{f.name}"
    if allowed is not None:
        s = src.const("A", allowed)
        cond = f"not {s}.issuperset({var})" if f.repeat else f"{var} not in {s}"
        kind = f.enum or f.type
        src.emit(depth, f"if {cond}: raise errors.FieldOutOfRange(f'{label}: {{{var}!r}} is not a valid {kind} value')")
    if rng is not None:
        lo, hi = rng
        cond = f"min({var}) < {lo} or max({var}) > {hi}" if f.repeat else f"not {lo} <= {var} <= {hi}"
        src.emit(depth, f"if {cond}: raise errors.FieldOutOfRange(f'{label}: {{{var}!r}} outside {lo}..{hi}')")


def _needs_checks(f: FieldDef) -> bool:
    return allowed_values(f) is not None or value_range(f) is not None or f.const is not None


def _emit_decode(src: _Source, depth: int, fields: tuple[FieldDef, ...], where: str) -> list[str]:
    """Emit statements decoding ``fields`` from ``buf`` at ``pos``; return the local names of user fields."""
    out: list[str] = []
    for run in _runs(fields):
        if isinstance(run, list):
            st = _struct_of(run)
            s, vals = src.const("S", st), src.name("v")
            src.emit(depth, f"{vals} = {s}.unpack_from(buf, pos)")
            src.emit(depth, f"pos += {st.size}")
            k = 0
            for f in run:
                expr = f"{vals}[{k}:{k + f.repeat}]" if f.repeat else f"{vals}[{k}]"
                k += f.repeat or 1
                if f.const is not None:
                    src.emit(
                        depth,
                        f"if {expr} != {f.const}: raise errors.FieldOutOfRange("
                        f"f'{where}.{f.name}: {{{expr}!r}}, the guide fixes it at {f.const}')",
                    )
                    continue
                var = src.name(f.name)
                src.emit(depth, f"{var} = {expr}")
                _emit_checks(src, depth, f, var, where)
                out.append(var)
            continue
        f = run
        var, n = src.name(f.name), src.name("n")
        src.emit(depth, f"{n} = _LEN.unpack_from(buf, pos)[0]")
        src.emit(depth, "pos += 4")
        if f.is_group:
            item_cls = src.const("C", make_item_class(f.item or f.name, f.fields))
            item_min = sum(min_size(g) for g in f.fields)
            src.emit(
                depth,
                f"if {n} < 0 or {n} * {item_min} > end - pos: raise errors.LengthMismatch("
                f"f'{where}.{f.name}: count {{{n}}} but only {{end - pos}} bytes remain')",
            )
            sizes = [fixed_size(g) for g in f.fields]
            simple = all(s is not None for s in sizes) and not any(g.repeat or _needs_checks(g) for g in f.fields)
            if simple:
                st = _struct_of(list(f.fields))
                s = src.const("S", st)
                chunk = f"buf[pos:pos + {n} * {st.size}]"
                src.emit(depth, f"{var} = _tuple(_map({item_cls}._make, {s}.iter_unpack({chunk})))")
                src.emit(depth, f"pos += {n} * {st.size}")
            else:
                items = src.name("items")
                src.emit(depth, f"{items} = []")
                src.emit(depth, f"for _ in _range({n}):")
                sub = _emit_decode(src, depth + 1, f.fields, f"{where}.{f.name}[]")
                src.emit(depth + 1, f"{items}.append({item_cls}._make(({', '.join(sub)},)))")
                src.emit(depth, f"{var} = _tuple({items})")
        else:
            src.emit(
                depth,
                f"if {n} < 0 or {n} > end - pos: raise errors.LengthMismatch("
                f"f'{where}.{f.name}: length {{{n}}} but only {{end - pos}} bytes remain')",
            )
            src.emit(depth, f"{var} = buf[pos:pos + {n}].decode('latin-1')")
            src.emit(depth, f"pos += {n}")
        out.append(var)
    return out


def _emit_encode(src: _Source, depth: int, fields: tuple[FieldDef, ...], names: list[str]) -> None:
    """Emit statements appending the encoding of ``fields`` (user values in locals ``names``) to ``parts``."""
    it = iter(names)
    for run in _runs(fields):
        if isinstance(run, list):
            args = []
            for f in run:
                if f.const is not None:
                    args.append(str(f.const))
                    continue
                var = next(it)
                args.append(f"*{var}" if f.repeat else var)
                if allowed_values(f) is not None or value_range(f) is not None:
                    check = "_ok_all" if f.repeat else "_ok"
                    src.emit(depth, f"if not {check}({src.const('F', f)}, {var}): raise _Bad")
            s = src.const("S", _struct_of(run))
            src.emit(depth, f"parts.append({s}.pack({', '.join(args)}))")
            continue
        f, var = run, next(it)
        if f.is_group:
            src.emit(depth, f"parts.append(_LEN.pack(len({var})))")
            sub = user_fields(f.fields)
            if all(fixed_size(g) is not None for g in f.fields) and not any(
                g.repeat or _needs_checks(g) for g in f.fields
            ):
                s = src.const("S", _struct_of(list(f.fields)))
                src.emit(depth, f"parts.extend(_starmap({s}.pack, {var}))")
            else:
                locs = [src.name(g.name) for g in sub]
                src.emit(depth, f"for _it in {var}:")
                src.emit(depth + 1, f"{', '.join(locs)}, = _it")
                _emit_encode(src, depth + 1, f.fields, locs)
        else:
            b = src.name("b")
            src.emit(depth, f"{b} = {var} if _isinstance({var}, (bytes, bytearray)) else {var}.encode('latin-1')")
            src.emit(depth, f"parts.append(_LEN.pack(len({b})))")
            src.emit(depth, f"parts.append({b})")


class _Bad(Exception):
    """Internal: a value failed a fast check; the slow path finds and names it."""


def _ok(f: FieldDef, v: Any) -> bool:
    allowed, rng = allowed_values(f), value_range(f)
    return (allowed is None or v in allowed) and (rng is None or rng[0] <= v <= rng[1])


def _ok_all(f: FieldDef, vs: Any) -> bool:
    return all(_ok(f, v) for v in vs)


def compile_telegram(tdef: TelegramDef, direction: Direction) -> tuple[type[Telegram], Decoder, Encoder]:
    """Build the class, decoder and encoder of one telegram in one direction."""
    where = f"{tdef.name}.{direction}"
    layout = tdef.layout(direction)
    if not tdef.layout_known or layout is None:
        opaque = make_telegram_class(tdef, direction, ["payload"])
        ident = bytes([tdef.id])

        def decode_opaque(buf: bytes) -> Telegram:
            return opaque._make((bytes(buf[1:]),))  # type: ignore[attr-defined, no-any-return]

        def encode_opaque(t: Telegram) -> bytes:
            payload = t[0]
            if not isinstance(payload, (bytes, bytearray)):
                raise errors.FieldValueError(f"{where}.payload: expected bytes, got {type(payload).__name__}")
            return ident + bytes(payload)

        return opaque, decode_opaque, encode_opaque

    names = [f.name for f in user_fields(layout)]
    cls = make_telegram_class(tdef, direction, names)

    dsrc = _Source(where + ".decode")
    dsrc.ns["_CLS"] = cls
    dsrc.emit(0, "def decode(buf):")
    dsrc.emit(1, "pos = 1")
    dsrc.emit(1, "end = len(buf)")
    dsrc.emit(1, "try:")
    dsrc.emit(2, "pass")
    local = _emit_decode(dsrc, 2, layout, tdef.name)
    dsrc.emit(1, "except errors.struct_error:")
    short = f"{tdef.name}: telegram of {{end}} bytes is shorter than its layout"
    dsrc.emit(2, f"raise errors.Truncated(f'{short}') from None")
    dsrc.emit(1, f"if pos != end: raise errors.TrailingBytes(f'{tdef.name}: {{end - pos}} bytes after the last field')")
    dsrc.emit(1, f"return _CLS._make(({', '.join(local)}{',' if local else ''}))")
    dsrc.ns["errors"] = _ErrorsNS
    decode: Decoder = dsrc.compile("decode")

    esrc = _Source(where + ".encode")
    esrc.ns.update(_Bad=_Bad, _ok=_ok, _ok_all=_ok_all, _ID=bytes([tdef.id]))
    evars = [esrc.name(n) for n in names]
    esrc.emit(0, "def encode(t):")
    if evars:
        esrc.emit(1, f"{', '.join(evars)}, = t")
    esrc.emit(1, "parts = [_ID]")
    _emit_encode(esrc, 1, layout, evars)
    esrc.emit(1, "return b''.join(parts)")
    fast_encode = esrc.compile("encode")

    def encode(t: Telegram) -> bytes:
        try:
            return fast_encode(t)  # type: ignore[no-any-return]
        except (_Bad, struct.error, TypeError, ValueError, AttributeError, OverflowError) as exc:
            for f, v in zip(user_fields(layout), t, strict=True):
                msg = check_value(f, v, tdef.name)
                if msg:
                    raise errors.FieldValueError(msg) from None
            raise errors.FieldValueError(f"{tdef.name}: {exc}") from None

    return cls, decode, encode


class _ErrorsNS:
    """The names generated decoders use: the error classes plus ``struct.error``."""

    struct_error = struct.error
    FieldOutOfRange = errors.FieldOutOfRange
    LengthMismatch = errors.LengthMismatch
    Truncated = errors.Truncated
    TrailingBytes = errors.TrailingBytes
