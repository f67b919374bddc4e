"""Reading TOML for armctl: one document as a dict, every failure a ProfileError naming its source.

Strategy: ``tomllib`` does the parsing; this module adds what it leaves open — the input must be
UTF-8 (a byte-order mark is dropped), whole numbers must be TOML's 64-bit ones and nesting is
bounded (``MAX_TOML_DEPTH``), checked iteratively so nothing can recurse out of stack.  A syntax
error leads with its place, ``FILE:LINE:COLUMN: invalid TOML: …``, as a script's errors do.  Bytes
in, a dict out: pure.  Reading the file (through the bounded reader, so ``/dev/zero`` is no
profile) is armctl/host/config_file.py's ``read_toml``, on the host's side with the other files.
"""

from __future__ import annotations

import re
import tomllib
from typing import Any

from ..errors import ProfileError

# TOML's own integer range (the spec: a whole number that is not a signed 64-bit one is an error);
# tomllib reads any length, and a 400-digit number overflows every float a check compares it with.
TOML_INT_RANGE = (-(2**63), 2**63 - 1)
MAX_TOML_DEPTH = 32  # tables and arrays nested deeper than this: no armctl setting is, and a check would recurse


def parse_toml(data: bytes, source: str) -> dict:
    """One TOML document as a dict; every failure (not UTF-8, invalid TOML, a whole number outside
    TOML's 64 bits, arrays or tables nested deeper than ``MAX_TOML_DEPTH``) is a ProfileError naming
    ``source``.  A UTF-8 byte-order mark is dropped, as a script's is."""
    try:
        text = data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as error:
        raise ProfileError(f"{source}: not UTF-8 text (byte {error.start})") from None
    try:
        parsed = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ProfileError(f"{source}{toml_error_place(error, text)}: invalid TOML: {toml_error_words(error)}") from None
    except RecursionError:
        raise ProfileError(f"{source}: invalid TOML: arrays or tables nested more than {MAX_TOML_DEPTH} deep") from None
    except ValueError:  # int() past sys.get_int_max_str_digits(): thousands of digits
        raise ProfileError(f"{source}: invalid TOML: a whole number outside {TOML_INT_RANGE[0]}…{TOML_INT_RANGE[1]}") from None
    _check_toml_values(parsed, source)
    return parsed


# where tomllib (3.11–3.13) puts the place of a syntax error: the end of its message
_PLACE = re.compile(r" \(at (?:line (\d+), column (\d+)|end of document)\)$")


def toml_error_place(error: tomllib.TOMLDecodeError, text: str) -> str:
    """``:LINE:COLUMN`` of tomllib's syntax error in ``text`` (1-based; "" if it names none): its
    ``lineno``/``colno`` where it has them (Python 3.14), else read from its message, as 3.11 to
    3.13 write it; "at end of document" is the place 3.14 gives it, past the last character."""
    line, column = getattr(error, "lineno", None), getattr(error, "colno", None)
    if isinstance(line, int) and isinstance(column, int):
        return f":{line}:{column}"
    match = _PLACE.search(str(error))
    if match is None:
        return ""
    if match.group(1):
        return f":{match.group(1)}:{match.group(2)}"
    document = text.replace("\r\n", "\n")  # as tomllib reads it
    line, column = document.count("\n") + 1, len(document) - document.rfind("\n")
    return f":{line}:{column}"


def toml_error_words(error: tomllib.TOMLDecodeError) -> str:
    """tomllib's message without the place it appends (``toml_error_place`` names it)."""
    words = getattr(error, "msg", None)
    return words if isinstance(words, str) else _PLACE.sub("", str(error))


def _check_toml_values(document: dict, source: str) -> None:
    """ProfileError naming the dotted key of the first whole number outside ``TOML_INT_RANGE`` or
    the first value nested deeper than ``MAX_TOML_DEPTH`` (iterative: no recursion to run out of)."""
    low, high = TOML_INT_RANGE
    pending: list[tuple[str, Any, int]] = [("", document, 0)]
    while pending:
        key, value, depth = pending.pop()
        if depth > MAX_TOML_DEPTH:
            raise ProfileError(f"{source}: {key} is nested more than {MAX_TOML_DEPTH} deep")
        if isinstance(value, dict):
            pending.extend((f"{key}.{k}" if key else k, v, depth + 1) for k, v in value.items())
        elif isinstance(value, list):
            pending.extend((f"{key}[{i}]", v, depth + 1) for i, v in enumerate(value))
        elif isinstance(value, int) and not isinstance(value, bool) and not low <= value <= high:
            raise ProfileError(f"{source}: {key} = {short_repr(value)} is outside TOML's whole numbers {low}…{high}")


def short_repr(value, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"
