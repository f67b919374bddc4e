"""Reading TOML for armctl: one document as a dict, every failure a ProfileError naming its source.

Strategy: ``tomllib`` does the parsing; this module adds what it leaves open — the input must be
UTF-8 (a byte-order mark is dropped), whole numbers must be TOML's 64-bit ones and nesting is
bounded (``MAX_TOML_DEPTH``), checked iteratively so nothing can recurse out of stack.  Bytes
in, a dict out: pure.  Reading the file (through the bounded reader, so ``/dev/zero`` is no
profile) is armctl/host/config_file.py's ``read_toml``, on the host's side with the other files.
"""

from __future__ import annotations

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
        raise ProfileError(f"{source}: invalid TOML: {error}") from None
    except RecursionError:
        raise ProfileError(f"{source}: invalid TOML: arrays or tables nested more than {MAX_TOML_DEPTH} deep") from None
    except ValueError:  # int() past sys.get_int_max_str_digits(): thousands of digits
        raise ProfileError(f"{source}: invalid TOML: a whole number outside {TOML_INT_RANGE[0]}…{TOML_INT_RANGE[1]}") from None
    _check_toml_values(parsed, source)
    return parsed


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
