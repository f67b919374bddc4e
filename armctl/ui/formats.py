"""Frames as text: the output formats of ``compile`` and the input formats of ``decode``.

Strategy: pure functions from frames to lines and from user input to bytes, so the CLI only
wires files to them.  ``decode`` accepts three inputs and tells them apart by content, never
by file name: hex text (whitespace ignored), armctl's JSON-lines log (one object per line with
a ``hex`` field), or raw bytes.
"""

from __future__ import annotations

import json
import math
import re
import string
from typing import TYPE_CHECKING, Iterable, Iterator

from ..core.protocol import Command, f32_repr

if TYPE_CHECKING:
    from ..core.status_frames import Chunk

# the bytes hex text is made of (decode judges a long input's first block with them too)
HEX_DIGIT_BYTES = frozenset(string.hexdigits.encode())
WHITESPACE_BYTES = frozenset(string.whitespace.encode())


def json_value(value):
    """Field values for JSON: floats in their shortest single-precision spelling; inf and NaN
    (a decoded frame may carry them) as the strings "inf", "-inf", "nan" — JSON has no such numbers."""
    if isinstance(value, float):
        text = f32_repr(value)
        if not math.isfinite(value):
            return text
        return float(text) if any(c in text for c in ".eE") else int(text)
    if isinstance(value, tuple):
        return [json_value(v) for v in value]
    return value


def frame_record(command: Command, frame: bytes, source: dict | None = None) -> dict:
    """One JSON object per frame: the command, its decoded fields, the bytes and the source."""
    record = {"command": type(command).__name__, "name": command.NAME}
    record["fields"] = {name: json_value(v) for name, v in command.fields().items()}
    record["hex"] = frame.hex()
    if source is not None:
        record["source"] = source
    return record


def looks_like_hex(data: bytes) -> bool:
    """True when the input is hex text: only hex digits and whitespace, an even count of digits."""
    digits = 0
    for byte in data:
        if byte in HEX_DIGIT_BYTES:
            digits += 1
        elif byte not in WHITESPACE_BYTES:
            return False
    return digits > 0 and digits % 2 == 0


_LOG_LINE = re.compile(rb"^\s*\{")


def looks_like_log(data: bytes) -> bool:
    """True when the input is a JSON-lines log whose records carry frames as ``hex``: every line
    starts as a JSON object does — or, a log with a damaged line (which ``decode`` must name,
    not read as raw bytes), its first line is a JSON object or a line is a sealed record."""
    data = data.lstrip()
    if data[:1] == b"{" and all(_LOG_LINE.match(line) for line in data.splitlines() if line.strip()):
        return True
    try:
        if isinstance(json.loads(data.split(b"\n", 1)[0]), dict):
            return True
    except (ValueError, RecursionError):
        pass
    return holds_sealed_record(data)


def holds_sealed_record(data: bytes) -> bool:
    """A line of ``data`` is an intact sealed record of a ``run --log`` (its CRC-32 matches: no
    chance in other bytes) — a log, whatever damage its first lines took."""
    from ..core.joblog import unseal

    return any(line.startswith(b'{"') and unseal(line.decode("utf-8", "replace")) is not None
               for line in data.split(b"\n"))


def bytes_from_input(data: bytes) -> bytes:
    """The byte stream ``decode`` should scan, whatever form the user gave it in."""
    if looks_like_hex(data):
        # whitespace anywhere, even inside a byte ("1 23 4"), only separates digits
        return bytes.fromhex("".join(data.decode("ascii").split()))
    if looks_like_log(data):
        return b"".join(_log_bytes(data))
    return data


def _log_bytes(data: bytes) -> Iterator[bytes]:
    for line in data.splitlines():
        if not line.strip():
            continue
        try:
            record = json.loads(line)
            yield bytes.fromhex(record["hex"])
        except (ValueError, KeyError, TypeError, RecursionError):
            # a log line without a frame (a note, a summary) carries no bytes; nor does one
            # that is no JSON object, or one nested too deeply for the parser
            continue


_DESCRIBED: dict[bytes, str] = {}  # a frame's bytes → its line after the offset (decode repeats many)
_DESCRIBED_MAX = 4096  # bounded: memory stays flat whatever the input


def describe_chunk(chunk: Chunk) -> str:
    if chunk.frame is not None:
        text = _DESCRIBED.get(chunk.data)
        if text is None:
            if len(_DESCRIBED) >= _DESCRIBED_MAX:
                _DESCRIBED.clear()
            text = _DESCRIBED[chunk.data] = _describe_frame(chunk)
        return f"{chunk.offset:>6}  {text}"
    where = f"{chunk.offset:>6}"
    if chunk.error is not None:
        return f"{where}  invalid  {chunk.error}: {chunk.data.hex(' ')}"
    return f"{where}  ??       {len(chunk.data)} byte(s) in no frame: {_short_hex(chunk.data)}"


def _describe_frame(chunk: Chunk) -> str:
    """A frame's line after its offset: family and description (the same bytes, the same line)."""
    from ..core.status_frames import StatusFrame, describe  # decode's: compile needs none of it (start-up)

    if isinstance(chunk.frame, StatusFrame):
        return f"status   {describe(chunk.frame)}"
    family = "motion " if chunk.data[0] == 0xEE else "control"
    return f"{family}  {describe(chunk.frame)}"


def chunk_record(chunk: Chunk) -> dict:
    """``decode --json``: one object per chunk — its offset and bytes, its family (motion,
    control, status, invalid, junk) and, for a frame, its name and decoded fields."""
    from ..core.status_frames import StatusFrame

    record = {"offset": chunk.offset, "hex": chunk.data.hex()}
    frame = chunk.frame
    if isinstance(frame, Command):
        record["family"] = "motion" if chunk.data[0] == 0xEE else "control"
        record.update(frame_record(frame, chunk.data))
    elif isinstance(frame, StatusFrame):
        record.update(family="status", kind=frame.KIND, name=type(frame).__name__)
        record["fields"] = {name: json_value(v) for name, v in frame.fields().items()}
    elif chunk.error is not None:
        record.update(family="invalid", error=chunk.error)
    else:
        record["family"] = "junk"
    return record


def _short_hex(data: bytes, limit: int = 24) -> str:
    if len(data) <= limit:
        return data.hex(" ")
    return data[:limit].hex(" ") + f" … (+{len(data) - limit})"


class ChunkTally:
    """``decode``'s closing count, kept as the chunks go by (none of them is kept)."""

    def __init__(self) -> None:
        from ..core.status_frames import StatusFrame

        self._status_class = StatusFrame
        self.commands = self.statuses = self.invalid = self.junk_bytes = 0

    def add(self, chunk: Chunk) -> None:
        if isinstance(chunk.frame, Command):
            self.commands += 1
        elif isinstance(chunk.frame, self._status_class):
            self.statuses += 1
        elif chunk.error is not None:
            self.invalid += 1
        else:
            self.junk_bytes += len(chunk.data)

    def line(self) -> str:
        return (f"{self.commands} command frame(s), {self.statuses} status frame(s), {self.invalid} invalid frame(s), "
                f"{self.junk_bytes} byte(s) in no frame")


def summary_line(chunks: Iterable[Chunk]) -> str:
    tally = ChunkTally()
    for chunk in chunks:
        tally.add(chunk)
    return tally.line()


def describe_decoded(item) -> str:
    """``describe_chunk`` of a ``decode.Decoded``, after its time and direction when a log gave them:
    ``    0.030 s  arm→host      0  status   position …``."""
    line = describe_chunk(item.chunk)
    if item.t_s is None and item.direction is None:
        return line
    when = f"{item.t_s:>9.3f} s" if item.t_s is not None else " " * 11
    return f"{when}  {DIRECTIONS.get(item.direction, '?       ')}  {line}"


def decoded_record(item) -> dict:
    """``chunk_record`` of a ``decode.Decoded``, with ``t`` (s, the log's clock) and ``direction``
    (``host->arm`` or ``arm->host``) when a log gave them."""
    record = chunk_record(item.chunk)
    if item.t_s is not None or item.direction is not None:
        record = {"t": item.t_s, "direction": _JSON_DIRECTIONS.get(item.direction), **record}
    return record


# A log record's direction (``dir``, run --log) → what decode prints and what its JSON says.  Here,
# with the other input formats: armctl/ui/decode.py reads the log's words from this table.
DIRECTIONS = {"tx": "host→arm", "rx": "arm→host"}
_JSON_DIRECTIONS = {"tx": "host->arm", "rx": "arm->host"}
