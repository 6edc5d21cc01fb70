"""Platform parameters ("properties"): guide 5.9 and 6.4 CMD_GET_PLTF_PARAM / CMD_GET_PLTF_PARAM_VEC.

Rules of this module:
- parameters.yaml is the only source of names, categories, types, ranges and defaults. It is read once,
  validated against parameters.schema.json, then checked for what JSON Schema cannot say (unique names,
  min <= default <= max, finite numbers, tab matches category) and turned into frozen `Parameter`s.
- Values are Python `bool` (BOOLEAN), `int` (INTEGER) and `float` (DOUBLE). Text crosses the wire only
  through `Parameter.parse` and `Parameter.format` (value strings: errata E-PAR-005, E-PAR-006).
- Names are exact and case-sensitive (E-PAR-003).
- Every refused name or value raises `ParameterError` (a ValueError) and changes nothing; a broken table
  raises `ParameterTableError`. Nothing else escapes `parse` for any `str`.
- Sans-IO: the only I/O is reading this package's own yaml/json files (or a table path given explicitly).
"""

from __future__ import annotations

import enum
import functools
import json
import math
import re
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, TypeAlias

import jsonschema
import yaml

Value: TypeAlias = bool | int | float

_HERE: Final = Path(__file__).resolve().parent
TABLE_PATH: Final = _HERE / "parameters.yaml"
SCHEMA_PATH: Final = _HERE / "parameters.schema.json"

_INT32_MIN: Final = -(2**31)
_INT32_MAX: Final = 2**31 - 1


class Category(enum.IntEnum):
    """guide 6.4 CMD_GET_PLTF_PARAM: "The category the parameter belongs to"."""

    GEOM = 0
    PLANNING = 1
    IPO = 2
    LOCALIZATION = 3
    TRACKING_DETECTION = 4
    COLLISION = 5
    SURVEILLANCE = 6
    MOTION_CTRL = 7
    MAPPING = 8
    USONIC = 9
    INFRARED = 10


class DataType(enum.IntEnum):
    """guide 6.4 CMD_GET_PLTF_PARAM: "The data type of the parameter"."""

    BOOLEAN = 0
    INTEGER = 1
    DOUBLE = 2


class ParameterError(ValueError):
    """A parameter name or value was refused (unknown, read-only, malformed, out of range)."""


class ParameterTableError(ValueError):
    """parameters.yaml (or a table given in its place) is broken."""


# guide 5.9: the tab of the property panel each parameter is listed under.
_TAB_CATEGORY: Final[Mapping[str, Category]] = {
    "Surveillance": Category.SURVEILLANCE,
    "Tracking & Detection": Category.TRACKING_DETECTION,
    "Ultrasonic": Category.USONIC,
    "Mapping": Category.MAPPING,
    "Motion Control": Category.MOTION_CTRL,
    "Planning": Category.PLANNING,
    "Collision": Category.COLLISION,
    "Geometry": Category.GEOM,
    "InfraRed": Category.INFRARED,
    "Interpolation": Category.IPO,
    "Localization": Category.LOCALIZATION,
}

# --- value text (E-PAR-005, E-PAR-006) -------------------------------------------------------------
_BLANKS: Final = " \t\r\n"
_BOOL_TEXT: Final[Mapping[str, bool]] = {"true": True, "1": True, "false": False, "0": False}
_INT_TEXT: Final = re.compile(r"[+-]?[0-9]+", re.ASCII)
_DOUBLE_TEXT: Final = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?", re.ASCII)


def _shown(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:36] + "...'"


def _parse_boolean(text: str) -> Value:
    value = _BOOL_TEXT.get(text.lower())
    if value is None:
        raise ValueError("expected true, false, 1 or 0")
    return value


def _parse_integer(text: str) -> Value:
    if not _INT_TEXT.fullmatch(text):
        raise ValueError("expected a decimal integer")
    return int(text)  # may raise ValueError beyond int_max_str_digits: refused like any bad text


def _parse_double(text: str) -> Value:
    if not _DOUBLE_TEXT.fullmatch(text):
        raise ValueError("expected a decimal number with '.' as decimal point")
    value = float(text)
    if not math.isfinite(value):
        raise ValueError("number too large")
    return value


_PARSERS: Final[Mapping[DataType, Callable[[str], Value]]] = {
    DataType.BOOLEAN: _parse_boolean,
    DataType.INTEGER: _parse_integer,
    DataType.DOUBLE: _parse_double,
}

_FORMATTERS: Final[Mapping[DataType, Callable[[Any], str]]] = {
    DataType.BOOLEAN: lambda value: "true" if value else "false",
    DataType.INTEGER: str,
    DataType.DOUBLE: repr,  # shortest text that reads back to the same float
}


@dataclass(frozen=True, slots=True)
class Parameter:
    """One row of the parameter table; `minimum`/`maximum` are the real, inclusive range."""

    name: str
    category: Category
    type: DataType
    default: Value
    unit: str | None
    minimum: int | float
    maximum: int | float
    description: str
    source: str
    writable: bool
    errata: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        _check_row(self)

    def parse(self, text: str) -> Value:
        """Value text (CMD_SET_PLTF_PARAM) -> value, type- and range-checked; else ParameterError."""
        try:
            value = _PARSERS[self.type](text.strip(_BLANKS))
        except ValueError as exc:
            raise ParameterError(f"{self.name}: invalid {self.type.name} value {_shown(text)}: {exc}") from None
        return self._in_range(value)

    def coerce(self, value: object) -> Value:
        """Check a Python value's type and range (an int is accepted for DOUBLE); else ParameterError."""
        checked: Value
        if self.type is DataType.BOOLEAN and isinstance(value, bool):
            checked = value
        elif isinstance(value, bool) or not isinstance(value, int | float):
            raise ParameterError(f"{self.name}: {_shown(value)} is not a {self.type.name} value")
        elif self.type is DataType.INTEGER and isinstance(value, int):
            checked = value
        elif self.type is DataType.DOUBLE:
            try:
                checked = float(value)
            except OverflowError:
                checked = math.inf
            if not math.isfinite(checked):
                raise ParameterError(f"{self.name}: {_shown(value)} is not a finite DOUBLE value")
        else:
            raise ParameterError(f"{self.name}: {_shown(value)} is not a {self.type.name} value")
        return self._in_range(checked)

    def format(self, value: Value) -> str:
        """Value -> canonical wire text: "true"/"false", decimal int, shortest float repr."""
        return _FORMATTERS[self.type](self.coerce(value))

    def wire_bounds(self) -> tuple[int, int]:
        """The INT min and max of the GET_PLTF_PARAM replies: the smallest integer interval holding the
        range, i.e. floor(min), ceil(max) for DOUBLE (E-PAR-004); BOOLEAN gives 0, 1."""
        return math.floor(self.minimum), math.ceil(self.maximum)

    def _in_range(self, value: Value) -> Value:
        if self.type is not DataType.BOOLEAN and not self.minimum <= value <= self.maximum:
            raise ParameterError(
                f"{self.name}: value {self._text(value)} out of range [{self._text(self.minimum)}, "
                f"{self._text(self.maximum)}]"
            )
        return value

    def _text(self, value: Value) -> str:
        return repr(float(value)) if self.type is DataType.DOUBLE else str(value)


def _check_row(row: Parameter) -> None:
    """What JSON Schema cannot state about one row; raises ParameterTableError."""
    problems: list[str] = []
    bounds = (row.minimum, row.maximum)
    if not all(isinstance(b, int | float) and not isinstance(b, bool) and math.isfinite(b) for b in bounds):
        problems.append("min and max must be finite numbers")
    elif row.minimum > row.maximum:
        problems.append(f"min {row.minimum} > max {row.maximum}")
    elif row.type is DataType.BOOLEAN and bounds != (0, 1):
        problems.append("a BOOLEAN has min 0 and max 1")
    elif row.type is DataType.INTEGER and not all(isinstance(b, int) for b in bounds):
        problems.append("an INTEGER has integer min and max")
    elif not _INT32_MIN <= math.floor(row.minimum) <= math.ceil(row.maximum) <= _INT32_MAX:
        problems.append("min and max must fit the INT (32 bit) of the GET_PLTF_PARAM reply")
    else:
        try:
            row.coerce(row.default)
        except ParameterError as exc:
            problems.append(f"default: {exc}")
    tab = row.source.removeprefix("guide 5.9 ")
    if tab != row.source and _TAB_CATEGORY.get(tab) is not row.category:
        problems.append(f"source tab {tab!r} does not match category {row.category.name}")
    if problems:
        raise ParameterTableError(f"parameter {row.name!r}: " + "; ".join(problems))


# --- the table --------------------------------------------------------------------------------------
@functools.cache
def _validator() -> jsonschema.protocols.Validator:
    schema = json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def _row(entry: Mapping[str, Any]) -> Parameter:
    data_type = DataType[entry["type"]]
    number: Callable[[Any], int | float] = float if data_type is DataType.DOUBLE else int
    default = entry["default"]
    return Parameter(
        name=entry["name"],
        category=Category[entry["category"]],
        type=data_type,
        default=default if data_type is DataType.BOOLEAN else number(default),
        unit=entry["unit"],
        minimum=number(entry["min"]),
        maximum=number(entry["max"]),
        description=entry["description"],
        source=entry["source"],
        writable=entry["writable"],
        errata=tuple(entry.get("errata", ())),
    )


def build_parameters(table: Any) -> dict[str, Parameter]:
    """A loaded table (the yaml's data) -> parameters by name, in table order; ParameterTableError."""
    error = jsonschema.exceptions.best_match(_validator().iter_errors(table))
    if error is not None:
        where = "/".join(str(part) for part in error.absolute_path) or "(top)"
        raise ParameterTableError(f"parameter table invalid at {where}: {error.message}")
    parameters: dict[str, Parameter] = {}
    for entry in table["parameters"]:
        row = _row(entry)
        if row.name in parameters:
            raise ParameterTableError(f"parameter {row.name!r} listed twice")
        parameters[row.name] = row
    return parameters


@functools.cache
def _default_table() -> tuple[Parameter, ...]:
    return tuple(load_parameters(TABLE_PATH).values())


def load_parameters(path: Path | str | None = None) -> dict[str, Parameter]:
    """The parameter table by name in file order (a fresh dict; the package's own table is cached)."""
    if path is None:
        return {row.name: row for row in _default_table()}
    try:
        table = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise ParameterTableError(f"{path}: not YAML: {exc}") from None
    return build_parameters(table)


# --- current values ---------------------------------------------------------------------------------
class ParameterStore:
    """The platform's current parameter values (guide 4.4, 5.9).

    `startup` holds value texts from the parameter files (guide 4.4: "read once at start-up"); they
    may set any parameter, read-only ones included. `set_text` is CMD_SET_PLTF_PARAM: writable
    parameters only. `reset` returns to the start-up values.
    """

    def __init__(
        self,
        parameters: Mapping[str, Parameter] | None = None,
        startup: Mapping[str, str] | None = None,
    ) -> None:
        self._parameters = dict(parameters) if parameters is not None else load_parameters()
        startup_values = {name: row.default for name, row in self._parameters.items()}
        for name, text in (startup or {}).items():
            startup_values[name] = self.parameter(name).parse(text)
        self._startup: Final = startup_values
        self._values = dict(startup_values)

    def parameter(self, name: str) -> Parameter:
        """The table row of `name` (exact, case-sensitive: E-PAR-003); else ParameterError."""
        row = self._parameters.get(name)
        if row is None:
            raise ParameterError(f"unknown parameter {_shown(name)}")
        return row

    def __contains__(self, name: object) -> bool:
        return name in self._parameters

    def __len__(self) -> int:
        return len(self._parameters)

    def get(self, name: str) -> Value:
        try:  # the values are keyed by the exact table names: one lookup on the motion loop's hot path
            return self._values[name]
        except KeyError:
            raise ParameterError(f"unknown parameter {_shown(name)}") from None

    def get_text(self, name: str) -> str:
        return self.parameter(name).format(self.get(name))

    def set_text(self, name: str, text: str) -> Value:
        """CMD_SET_PLTF_PARAM: set from value text and return the new value. On ParameterError
        (unknown, read-only, malformed, out of range: E-PAR-007, E-PAR-024) the old value stays."""
        row = self.parameter(name)
        if not row.writable:
            raise ParameterError(f"{name}: read-only parameter (set in the parameter file at start-up)")
        value = row.parse(text)
        self._values[name] = value
        return value

    def items(self) -> Iterator[tuple[Parameter, Value]]:
        """(row, current value) in table order: the order of CMD_GET_PLTF_PARAM_VEC (E-PAR-026)."""
        for name, row in self._parameters.items():
            yield row, self._values[name]

    def reset(self) -> None:
        """Back to the start-up values (defaults, then the `startup` texts)."""
        self._values = dict(self._startup)
