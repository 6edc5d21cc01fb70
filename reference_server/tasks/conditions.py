"""The goto condition language of E-XML-013: ``true|false|1|0`` or ``OPERAND==VALUE`` / ``OPERAND!=VALUE``.

OPERAND is ``DIn`` (IO board digital input n, 1..16), ``DOn`` (IO board digital output n, 1..12) or
``param:KEY``. DI/DO compare as integers 0/1; a parameter compares by its type (BOOLEAN true/false/1/0 as
booleans, INTEGER/DOUBLE numerically); an unknown key, or a VALUE that is not of the parameter's type, is a
task error. The schema has checked the syntax already; ``evaluate`` re-checks it and raises TaskError.
"""

from __future__ import annotations

import re

from pltf.reference_server.tasks.facade import Sensors, TaskError
from pltf.spec.parameters import DataType

_LITERAL = {"true": True, "1": True, "false": False, "0": False}
_COMPARISON = re.compile(r"(?:(DI|DO)([0-9]+)|param:([A-Za-z_][A-Za-z0-9_.\-]*))(==|!=)([A-Za-z0-9_.+\-]+)")
_BOOL_TEXT = {"true": True, "1": True, "false": False, "0": False}


def _typed(data_type: DataType, text: str, what: str) -> bool | float:
    text = text.strip()
    try:
        if data_type == DataType.BOOLEAN:
            return _BOOL_TEXT[text.lower()]
        return float(text)  # INTEGER and DOUBLE compare numerically: 600 == 600.0
    except (KeyError, ValueError):
        kind = "BOOLEAN" if data_type == DataType.BOOLEAN else "number"
        raise TaskError(f"{what}: {text!r} is not a {kind}") from None


def evaluate(condition: str, sensors: Sensors) -> bool:
    """Whether the goto jumps; TaskError for an unknown parameter or a value of the wrong type."""
    literal = _LITERAL.get(condition)
    if literal is not None:
        return literal
    match = _COMPARISON.fullmatch(condition)
    if match is None:
        raise TaskError(f"condition {condition!r}: not in the condition language (E-XML-013)")
    io, number, key, op, value = match.groups()
    if io is not None:
        n = int(number)
        limit = 16 if io == "DI" else 12
        if not 1 <= n <= limit:
            raise TaskError(f"condition {condition!r}: {io}{n} does not exist ({io}1..{io}{limit})")
        actual: bool | float = sensors.digital_input(n) if io == "DI" else sensors.digital_output(n)
        expected = _typed(DataType.INTEGER, value, f"condition {condition!r}")
    else:
        data_type, text = sensors.parameter(key)
        actual = _typed(data_type, text, f"parameter {key}")
        expected = _typed(data_type, value, f"condition {condition!r}")
    return (actual == expected) == (op == "==")
