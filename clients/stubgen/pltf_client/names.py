"""The Python names of the client's generated modules: a command's method, a reply's class, a field with its unit.

Rules:
- The word helpers (``snake``, ``pascal``, ``safe``) are ``pltf.stubgen.model``'s, shared with every language.
- One method per command, named after it (``CMD_MOVE_ABS`` -> ``move_abs``; a Python keyword gets a trailing
  ``_``). Reply classes are named after the GET_* command without ``CMD_GET_`` (``CMD_GET_STATUS`` -> ``Status``);
  repeated-group items after the spec's ``item``.
- Names of arguments and reply attributes carry the guide's unit (``x_mm``, ``angle_mdeg``), per ``UNIT_SUFFIX``;
  an unknown unit stops the generator, so a spec edit cannot slip through without a name.
"""

from __future__ import annotations

import keyword
from collections.abc import Sequence

from pltf.stubgen.model import Field, pascal, safe, snake

KEYWORDS = frozenset(keyword.kwlist)
# The guide's unit -> the suffix of the Python name. "1000*deg" is a millidegree, "1/1000*rad/s" and
# "1000*rad/s" both a milliradian per second (erratum E-REP-005), "1/100*deg/s" a centidegree per second.
UNIT_SUFFIX: dict[str, str] = {
    "mm": "mm",
    "mm/s": "mm_s",
    "1000*deg": "mdeg",
    "deg": "deg",
    "rad": "rad",
    "rad/s": "rad_s",
    "1000*rad/s": "mrad_s",
    "1/1000*rad/s": "mrad_s",
    "1/100*deg/s": "cdeg_s",
    "1/10000*m/s^2": "m_s2_x1e4",
    "1/10000*rad": "rad_x1e4",
    "1/10000*degC": "degc_x1e4",
    "degC": "degc",
    "mV": "mv",
    "ms": "ms",
    "s": "s",
    "%": "pct",
    "Byte/s": "bytes_s",
    "1/s": "per_s",
}
# Names that already say their unit keep it.
UNIT_ALREADY_NAMED: dict[str, tuple[str, ...]] = {"%": ("_percent",), "Byte/s": ("_per_s",), "1/s": ("_per_s",)}
SCALAR_PY = {"BYTE": "int", "INT16": "int", "INT": "int", "DOUBLE": "float", "BOOL": "bool", "STRING": "str"}


class GeneratorError(SystemExit):
    """A spec the generator cannot name: stops ``python -m pltf.client._generate`` with one line."""

    def __init__(self, message: str) -> None:
        super().__init__(f"pltf.client._generate: {message}")


def method_name(command: str) -> str:
    """``CMD_MOVE_ABS`` -> ``move_abs``, ``CMD_BREAK`` -> ``break_``."""
    return safe(snake(command.removeprefix("CMD_")), KEYWORDS)


def reply_class_name(command: str) -> str:
    """``CMD_GET_STATUS`` -> ``Status``, ``CMD_GET_PLTF_PARAM_VEC`` -> ``PltfParamVec``."""
    return pascal(command.removeprefix("CMD_GET_"))


def item_name(f: Field) -> str:
    """The class of a repeated group's items: the spec's ``item``, else the group's name."""
    return f.item or pascal(f.name)


def py_name(f: Field, owner: str = "") -> str:
    """The field's Python name: its spec name plus its unit (``angle`` in 1000*deg -> ``angle_mdeg``).

    In a group item (a NamedTuple, ``owner`` its class) a name that is a tuple method gets the item's name
    in front (``Cluster.index`` -> ``cluster_index``).
    """
    if owner and f.name in dir(tuple):
        return f"{owner.lower()}_{f.name}"
    if f.unit is None:
        return f.name
    if f.unit not in UNIT_SUFFIX:
        raise GeneratorError(f"no Python suffix for unit {f.unit!r} of field {f.name}: add it to UNIT_SUFFIX")
    if f.name.endswith(UNIT_ALREADY_NAMED.get(f.unit, ())):
        return f.name
    return f"{f.name}_{UNIT_SUFFIX[f.unit]}"


def check_unique(names: Sequence[str], where: str) -> None:
    dupes = {n for n in names if names.count(n) > 1}
    if dupes:
        raise GeneratorError(f"{where}: duplicate Python names {sorted(dupes)}")


def is_bool(f: Field) -> bool:
    return f.type == "BOOL" or f.enum == "Flag"


def scalar_type(f: Field, direction: str) -> str:
    """The Python type of one value: ``bool`` for flags, the IntEnum, the document's bytes for XML."""
    if is_bool(f):
        return "bool"
    if f.enum is not None:
        return f.enum
    if f.type == "XML":
        return "bytes" if direction == "reply" else "str | bytes"
    return SCALAR_PY[f.type]
