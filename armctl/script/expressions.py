"""Values written as expressions: ``#<name>``, ``[expr]`` with + − * / and unary minus.

Strategy: the parser turns a literal number into a plain ``float`` and anything else into a
small tree of frozen nodes (``Parameter``, ``Negate``, ``Binary``), each carrying its columns
on the line.  ``evaluate(value, parameters)`` is the one way to get a number out of either;
it raises ``ExpressionError`` (with a diagnostic code and the columns to point at) for an
undefined parameter (E007), a division by zero or a result too large for a float (E009), and
``Unavailable`` when a parameter is ``POISONED`` (its own assignment failed and was reported).
Parameters are LinuxCNC-style named globals, case-insensitive (names are stored lower-case).
"""

from __future__ import annotations

import math
from typing import Mapping, Union

from ..core.records import record


class _Poisoned:
    """The value of something whose error is already reported (see armctl/script/modal.py)."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "POISONED"


POISONED = _Poisoned()


class Unavailable(Exception):
    """A value depends on a POISONED one: skip it quietly, its error is already reported."""


class ExpressionError(Exception):
    """An expression that has no value; ``column``/``end_column`` locate it on its line."""

    def __init__(self, code: str, message: str, column: int, end_column: int, hint: str | None = None):
        super().__init__(message)
        self.code, self.message, self.hint = code, message, hint
        self.column, self.end_column = column, end_column


@record(slots=True)
class Parameter:
    """``#<name>`` — the current value of a named parameter (``name`` is lower-case)."""

    name: str
    column: int
    end_column: int

    def evaluate(self, parameters: Mapping[str, float]) -> float:
        try:
            value = parameters[self.name]
        except KeyError:
            raise ExpressionError(
                "E007", f"parameter #<{self.name}> is not defined", self.column, self.end_column,
                f"assign it on an earlier line: #<{self.name}> = 0",
            ) from None
        if value is POISONED:
            raise Unavailable(self.name)
        return value

    def __str__(self) -> str:
        return f"#<{self.name}>"


@record(slots=True)
class Negate:
    """``-value``."""

    operand: "Value"
    column: int
    end_column: int

    def evaluate(self, parameters: Mapping[str, float]) -> float:
        return -evaluate(self.operand, parameters)

    def __str__(self) -> str:
        return f"-{format_value(self.operand)}"


_OPERATIONS = {
    "+": float.__add__,
    "-": float.__sub__,
    "*": float.__mul__,
    "/": float.__truediv__,
}


@record(slots=True)
class Binary:
    """``left op right`` with ``op`` one of + - * /; the columns span both operands."""

    operator: str
    left: "Value"
    right: "Value"
    column: int
    end_column: int

    def evaluate(self, parameters: Mapping[str, float]) -> float:
        left = evaluate(self.left, parameters)
        right = evaluate(self.right, parameters)
        if self.operator == "/" and right == 0:
            raise ExpressionError("E009", f"division by zero in {self}", self.column, self.end_column)
        result = _OPERATIONS[self.operator](left, right)
        if math.isnan(result):  # inf - inf, inf * 0, inf / inf: no size at all, so not "too large"
            raise ExpressionError("E009", f"{self} is not a number (NaN): an infinite operand makes it undefined",
                                  self.column, self.end_column)
        if not math.isfinite(result):
            raise ExpressionError("E009", f"{self} is too large to be a number", self.column, self.end_column)
        return result

    def __str__(self) -> str:
        return f"[{format_value(self.left)} {self.operator} {format_value(self.right)}]"


Expression = Union[Parameter, Negate, Binary]
Value = Union[float, Expression]


def evaluate(value: Value, parameters: Mapping[str, float]) -> float:
    """The number a value stands for now; raises ``ExpressionError``."""
    if type(value) is float:
        return value
    return value.evaluate(parameters)


def format_value(value: Value) -> str:
    """A value written back as source text (numbers in their shortest form)."""
    if type(value) is float:
        if math.isfinite(value) and value == int(value) and abs(value) < 1e15:
            return str(int(value))
        return repr(value)
    return str(value)
