"""Put the probe's values into the ``[connector]`` table of an armctl.toml, keeping the rest.

Strategy: a small text edit of one table, not a TOML writer: every byte outside the keys set
is kept as it was (comments, other tables, key order, blank lines).  The file must parse
(tomllib) before and after; a key is replaced in place (a comment after its value is kept), a
new key goes after the table's last key, a missing table is appended; a key taken out (measured
on another arm: ``keep.measured_elsewhere``) loses its line.  ``connector`` given in
any other form (dotted keys, an inline table, not a table) is refused: edit it by hand.
Pure text in, text out (``updated``); ``write_connector`` is the thin file edge.

Why not tomlkit (weighed for issue 26): it writes dotted keys and inline tables, which this
refuses with the exact lines to set by hand, but on the form the probe itself writes — one
``[connector]`` table — it puts a new key after the comment that introduces the next table
(``fifo_frames = 50`` / blank / ``# next`` / ``speed_factor = 1.25`` / ``[jog]``), and it is one
more dependency for one rare form.  It does not clearly beat this editor, so it is not used.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from ..core.toml_reading import toml_error_place, toml_error_words
from ..errors import ConfigError

TABLE = "connector"
_HEADER = re.compile(r"^\s*\[\s*connector\s*\]\s*(#.*)?$")
_ANY_HEADER = re.compile(r"^\s*\[")
# a simple scalar value (what the probe writes and what a hand would): a string, number or bool
_VALUE = r'("(?:[^"\\]|\\.)*"|\'[^\']*\'|[-+0-9.eE_infa]+|true|false)'


def toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    return '"' + str(value).replace("\\", "\\\\").replace('"', '\\"') + '"'


def parse(text: str, where: str) -> dict:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"{where}{toml_error_place(error, text)}: not valid TOML ({toml_error_words(error)}): not "
                          "written; fix or move it first") from None


def updated(text: str, values: dict, where: str = "armctl.toml", drop=()) -> str:
    """``text`` with ``values`` set in its ``[connector]`` table, and the keys ``drop`` taken out of it."""
    text = _without(text, drop, where) if drop else text
    data = parse(text, where)
    lines = text.splitlines(keepends=True)
    headers = [k for k, line in enumerate(lines) if _HEADER.match(line)]
    if TABLE in data and (len(headers) != 1 or not isinstance(data[TABLE], dict)):
        raise ConfigError(f"{where}: `{TABLE}` is not written as one [{TABLE}] table: set these by hand: "
                          + ", ".join(f"{k} = {toml_value(v)}" for k, v in values.items()))
    if not headers:
        tail = "" if not text or text.endswith("\n") else "\n"
        body = "".join(f"{key} = {toml_value(value)}\n" for key, value in values.items())
        result = text + tail + ("\n" if text.strip() else "") + f"[{TABLE}]\n" + body
    else:
        start = headers[0] + 1
        end = next((k for k in range(start, len(lines)) if _ANY_HEADER.match(lines[k])), len(lines))
        for key, value in values.items():
            pattern = re.compile(rf"^(\s*{re.escape(key)}\s*=\s*){_VALUE}(\s*(#.*)?)$", re.S)
            for k in range(start, end):
                match = pattern.match(lines[k].rstrip("\r\n"))
                if match:
                    newline = lines[k][len(lines[k].rstrip("\r\n")):]
                    lines[k] = match.group(1) + toml_value(value) + match.group(3) + newline
                    break
                if re.match(rf"^\s*{re.escape(key)}\s*=", lines[k]):
                    raise ConfigError(f"{where}: [{TABLE}] {key} has a value the probe does not replace: "
                                      f"set {key} = {toml_value(value)} by hand")
            else:
                insert_at = _after_last_key(lines, start, end)
                lines.insert(insert_at, f"{key} = {toml_value(value)}\n")
                end += 1
        result = "".join(lines)
    check = parse(result, where)
    for key, value in values.items():
        if check[TABLE].get(key) != value:  # pragma: no cover - the edit above is wrong
            raise ConfigError(f"{where}: could not set [{TABLE}] {key}")
    return result


def _without(text: str, keys, where: str) -> str:
    """``text`` without the lines that set ``keys`` in its one ``[connector]`` table."""
    lines = text.splitlines(keepends=True)
    start = next(k for k, line in enumerate(lines) if _HEADER.match(line)) + 1
    end = next((k for k in range(start, len(lines)) if _ANY_HEADER.match(lines[k])), len(lines))
    for key in keys:
        found = [k for k in range(start, end) if re.match(rf"^\s*{re.escape(key)}\s*=", lines[k])]
        simple = re.compile(rf"^\s*{re.escape(key)}\s*=\s*{_VALUE}\s*(#.*)?$")
        if any(not simple.match(lines[k].rstrip("\r\n")) for k in found):
            raise ConfigError(f"{where}: [{TABLE}] {key} has a value the probe does not take out: remove it by hand")
        for k in reversed(found):
            del lines[k]
            end -= 1
    return "".join(lines)


def _after_last_key(lines: list[str], start: int, end: int) -> int:
    """Where a new key goes: after the table's last key line (not after trailing blank lines or
    comments that introduce the next table)."""
    last = start
    for k in range(start, end):
        stripped = lines[k].strip()
        if stripped and not stripped.startswith("#"):
            last = k + 1
    if last > 0 and not lines[last - 1].endswith("\n"):
        lines[last - 1] += "\n"
    return last


def check_writable(path: Path) -> None:
    """Before the probe sends anything: an existing file must be a regular file (the write
    replaces it: a device such as /dev/full must never be) and valid TOML (a missing directory:
    the option's type, ``cli_types.NamedFile``)."""
    updated(_existing_text(path), {}, str(path))


def _existing_text(path: Path) -> str:
    """The file's text, "" if there is none; read bounded, as every armctl.toml is (an endless
    input is an error, not a hang)."""
    from ..host.inputs import MAX_TOML_BYTES, read_file_bounded

    if not path.exists():
        return ""
    if not path.is_file():
        raise ConfigError(f"{path} is not a regular file: --write writes an armctl.toml")
    try:
        return read_file_bounded(str(path), limit_bytes=MAX_TOML_BYTES).decode("utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"cannot read {path}: {error}") from None


def write_connector(path: Path, values: dict, drop=()) -> None:
    """The file with ``values`` in its ``[connector]`` table, replaced atomically as ``compile -o``
    replaces its output (armctl/host/outputs.py): through a symbolic link to its target, keeping
    the file's mode; an error names ``path``."""
    from ..host.outputs import PendingOutput

    result = updated(_existing_text(path), values, str(path), drop)
    with PendingOutput(str(path), binary=False) as output:
        output.stream.write(result)
        output.commit()


def connector_table(path: Path) -> dict:
    """The ``[connector]`` table the file at ``path`` holds now ({} without one)."""
    table = parse(_existing_text(path), str(path)).get(TABLE, {})
    return table if isinstance(table, dict) else {}
