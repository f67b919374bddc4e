"""``armctl decode``, streaming: frames named as the input is read, in memory flat in its size.

Strategy: the input is read in blocks, never whole.  Its form is decided on its first block
(``PROBE_BYTES``; an input no longer than that is judged whole, exactly as
``formats.bytes_from_input`` judges it): a JSON-lines log (``run --log``), hex text, or raw bytes.
Bytes go through a ``FrameScanner`` — ``scan_frames`` fed piecewise: it decides at a position
only once a whole command frame's worth of bytes lies ahead (or the input ended), so it finds
exactly the chunks ``scan_frames`` finds on the whole input (a status frame, 9 bytes, is decided
once 9 bytes lie ahead of a byte that cannot start a command frame), and it keeps only the bytes it has
not decided yet (a run of stray bytes is handed out in pieces of at most ``JUNK_PIECE_BYTES``).

A log's records carry a time (``t``, the arm's clock) and a direction (``tx``: host→arm,
``rx``: arm→host); each direction is its own byte stream with its own scanner (a frame never
spans the two), and each frame is given the time of the record its first byte came in.  Frames
come out in the log's order, so the two directions interleave by time, not by byte offset;
a chunk's ``offset`` counts the bytes of its own direction.  A log record that is no JSON object
with a ``hex`` string carries no bytes (a note, a progress record).  Only a log's intact prefix
is trusted, as ``--resume`` trusts it (armctl/core/joblog.py: SQLite's recovery stops at the
first bad frame): the first line that is not JSON, or — once a sealed record (``run --log``'s:
place and CRC-32) was seen — no intact sealed record in its place, ends the decoding: its bytes
and everything after it may not be what was written, so the CLI names its line and exits 1 —
unless it is the torn last line a crash leaves (``joblog.torn``), which is named and ignored.

Pure but for reading the stream it is given: no printing (the CLI formats each ``Decoded``).
"""

from __future__ import annotations

import json
import re
import string
from collections import deque
from dataclasses import dataclass
from typing import BinaryIO, Iterator

from .formats import (  # noqa: F401 - DIRECTIONS: the log's words, offered here too
    DIRECTIONS, HEX_DIGIT_BYTES, WHITESPACE_BYTES, holds_sealed_record, looks_like_hex, looks_like_log,
)
from ..host.inputs import MAX_INPUT_BYTES, read_blocks_bounded, split_lines
from ..core.joblog import damage_of, in_place, intact, torn
from ..core.protocol import CONTROL_HEAD, FRAME_SIZE, MOTION_HEAD, STATUS_HEAD, STATUS_SIZE
from ..core.status_frames import Chunk, chunk_at

PROBE_BYTES = 1 << 16  # an input up to this size is judged whole, as before streaming
BLOCK_BYTES = 1 << 16
JUNK_PIECE_BYTES = 1 << 16  # a longer run of stray bytes comes out in pieces of this size

_COMMAND_HEADS = frozenset((MOTION_HEAD, CONTROL_HEAD))
_HEADS = _COMMAND_HEADS | {STATUS_HEAD}
_NEXT_HEAD = re.compile(b"[" + re.escape(bytes(sorted(_HEADS))) + b"]")


class NotHex(Exception):
    """Hex text (judged on its first block) with a byte that is not a hex digit later on;
    ``where``: its ``LINE:COLUMN`` (1-based), as every input error names it."""

    def __init__(self, message: str, where: str | None = None) -> None:
        super().__init__(message)
        self.where = where


@dataclass(frozen=True)
class Decoded:
    """A chunk of the input, with the time and direction its log record gave (None otherwise)."""

    chunk: Chunk
    t_s: float | None = None
    direction: str | None = None  # "tx" (host→arm) or "rx" (arm→host)


class FrameScanner:
    """``scan_frames`` fed piece by piece: ``feed(data)`` → the chunks decided so far,
    ``finish()`` → the rest; offsets count from the first byte fed."""

    def __init__(self) -> None:
        self._buffer = b""
        self._base = 0  # the offset of _buffer[0]
        self._position = 0  # the next index of _buffer to decide
        self._junk_start = 0  # the index where the undecided run of stray bytes begins

    def feed(self, data: bytes) -> list[Chunk]:
        self._buffer = self._buffer + data if self._buffer else bytes(data)
        return self._scan(final=False)

    def finish(self) -> list[Chunk]:
        return self._scan(final=True)

    def _scan(self, final: bool) -> list[Chunk]:
        buffer, position, junk_start, base = self._buffer, self._position, self._junk_start, self._base
        out: list[Chunk] = []
        size = len(buffer)
        while position < size:
            ahead = size - position
            if not final and (ahead < FRAME_SIZE if buffer[position] in _COMMAND_HEADS else ahead < STATUS_SIZE):
                break  # what lies here depends on bytes not fed yet
            chunk = chunk_at(buffer, position) if buffer[position] in _HEADS else None
            if chunk is None:
                # no frame starts before the next head byte: skip to it at C speed (/dev/zero)
                found = _NEXT_HEAD.search(buffer, position + 1)
                position = found.start() if found else size
                while position - junk_start >= JUNK_PIECE_BYTES:
                    out.append(Chunk(base + junk_start, buffer[junk_start:junk_start + JUNK_PIECE_BYTES]))
                    junk_start += JUNK_PIECE_BYTES
                continue
            if position > junk_start:
                out.append(Chunk(base + junk_start, buffer[junk_start:position]))
            out.append(Chunk(base + position, chunk.data, chunk.frame, chunk.error))
            position += len(chunk.data)
            junk_start = position
        if final and len(buffer) > junk_start:
            out.append(Chunk(base + junk_start, buffer[junk_start:]))
            junk_start = position = len(buffer)
        # keep only what is undecided: the stray run so far and the bytes ahead
        keep = min(junk_start, position)
        self._buffer, self._base = buffer[keep:], base + keep
        self._position, self._junk_start = position - keep, junk_start - keep
        return out


def decode_stream(stream: BinaryIO, name: str, limit_bytes: int = MAX_INPUT_BYTES,
                  damaged: list | None = None, jobs: list | None = None) -> Iterator[Decoded]:
    """Every chunk of ``stream`` in order (``InputTooLarge`` past ``limit_bytes``, ``NotHex``
    for hex text that stops being hex beyond its first block); a log's chunks up to its first
    damaged line, which goes to ``damaged`` as a ``LogDamage`` (a torn last line too, ``torn``
    set); its intact job records (which script, from which line, on which port) go to ``jobs``
    as (line number, record)."""
    blocks = read_blocks_bounded(stream, name, limit_bytes, BLOCK_BYTES)
    first = b""
    for block in blocks:  # the probe: up to PROBE_BYTES, or the whole input
        first += block
        if len(first) >= PROBE_BYTES:
            break
    ended = len(first) < PROBE_BYTES
    rest = iter(()) if ended else blocks
    if _looks_like_log(first, ended):
        yield from _log_chunks(first, rest, [] if damaged is None else damaged, [] if jobs is None else jobs)
    elif _looks_like_hex(first, ended):
        yield from (Decoded(chunk) for chunk in _scan_all(_hex_bytes(first, rest)))
    else:
        yield from (Decoded(chunk) for chunk in _scan_all(_chain(first, rest)))


def _chain(first: bytes, rest: Iterator[bytes]) -> Iterator[bytes]:
    for start in range(0, len(first), BLOCK_BYTES):
        yield first[start:start + BLOCK_BYTES]
    yield from rest


def _scan_all(blocks: Iterator[bytes]) -> Iterator[Chunk]:
    scanner = FrameScanner()
    for block in blocks:
        yield from scanner.feed(block)
    yield from scanner.finish()


def _looks_like_hex(first: bytes, ended: bool) -> bool:
    """Only hex digits and whitespace (an even count of digits when the whole input is here)."""
    if ended:
        return looks_like_hex(first)
    return all(byte in HEX_DIGIT_BYTES or byte in WHITESPACE_BYTES for byte in first)


def _hex_bytes(first: bytes, rest: Iterator[bytes]) -> Iterator[bytes]:
    """The bytes hex text spells (whitespace anywhere only separates digits)."""
    pending = ""  # a digit whose partner is in the next block
    line, column = 1, 1  # where this block starts
    for block in _chain(first, rest):
        text = block.decode("ascii", "replace")
        digits = pending + "".join(text.split())
        try:
            whole = len(digits) - len(digits) % 2
            yield bytes.fromhex(digits[:whole])
        except ValueError:
            bad = next(i for i, char in enumerate(text) if not (char in string.hexdigits or char.isspace()))
            before = text.count("\n", 0, bad)
            at = bad - text.rfind("\n", 0, bad) if before else column + bad
            raise NotHex(f"not hex text: {block[bad:bad + 1].decode('latin-1')!r}", f"{line + before}:{at}") from None
        pending = digits[whole:]
        newlines = text.count("\n")
        line, column = line + newlines, len(text) - text.rfind("\n") if newlines else column + len(text)
    if pending:
        raise NotHex("hex text ends with half a byte (an odd count of digits)")


def _looks_like_log(first: bytes, ended: bool) -> bool:
    if ended:
        return looks_like_log(first)
    return first.lstrip()[:1] == b"{" or holds_sealed_record(first)


def _log_lines(first: bytes, rest: Iterator[bytes]) -> Iterator[bytes]:
    return split_lines(_chain(first, rest))


@dataclass(frozen=True)
class LogDamage:
    """The line of a log that ended the decoding: its ``number``, ``why`` it is no intact record,
    how many non-blank lines ``after`` it were not decoded, and whether it is the ``torn`` last
    line a crash leaves (no damage)."""

    number: int
    why: str
    after: int = 0
    torn: bool = False


def _log_chunks(first: bytes, rest: Iterator[bytes], damaged: list, jobs: list) -> Iterator[Decoded]:
    """Each record's bytes into its direction's scanner; each chunk with the time of the
    record its first byte came in; up to the first damaged line (``_Prefix``), which goes to
    ``damaged``; an intact job record goes to ``jobs``."""
    scanners: dict[str | None, tuple[FrameScanner, deque]] = {}
    prefix = _Prefix()
    lines = _log_lines(first, rest)
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        record = prefix.record(line)
        if isinstance(record, _Damaged):  # the intact prefix ends here
            text = line.decode("utf-8", "replace")
            if torn(text.rstrip("\n"), text.endswith("\n")):
                damaged.append(LogDamage(number, record.why, torn=True))
            else:
                damaged.append(LogDamage(number, record.why, sum(1 for later in lines if later.strip())))
            break
        if isinstance(record, dict) and record.get("dir") == "job":
            jobs.append((number, record))
        data, t_s, direction = _frame_of(record)
        if data is None:
            continue
        scanner, marks = scanners.setdefault(direction, (FrameScanner(), deque()))
        marks.append((scanner._base + len(scanner._buffer), t_s))  # where this record's bytes start
        yield from _timed(scanner.feed(data), marks, direction)
    for direction, (scanner, marks) in scanners.items():
        yield from _timed(scanner.finish(), marks, direction)


_TOO_DEEP = object()  # a JSON value nested too deep for the parser


@dataclass(frozen=True)
class _Damaged:
    why: str  # why the line is no intact record (``joblog.damage_of``'s words)


class _Prefix:
    """The journal's rule of trust (armctl/core/joblog.py), line by line: ``record(line)`` → the
    line's JSON value (a sealed record's ``crc`` and ``seq`` taken out), or why it ends the
    intact prefix: it is not JSON, or it is no intact sealed record in its place where the log
    is sealed (a record with ``crc`` or ``seq`` was seen: from then on a key a flipped bit hit
    is no excuse).  A hand-made log, or one of format 1, without seals, is read as before."""

    def __init__(self) -> None:
        self.sealed = False
        self.expected = 0  # the ``seq`` due next

    def record(self, line: bytes):
        """The line's JSON value (None: nested too deep, no seals), or ``_Damaged``."""
        text = line.decode("utf-8", "replace")
        try:
            value = json.loads(text)
        except RecursionError:
            value = _TOO_DEEP
        except ValueError:
            return _Damaged(damage_of(text))
        if not self.sealed and not (isinstance(value, dict) and ("crc" in value or "seq" in value)):
            return None if value is _TOO_DEEP else value  # no seals: nothing tells its bytes were written
        self.sealed = True
        if not isinstance(value, dict) or not intact(value):  # (``intact`` takes the crc out)
            return _Damaged(damage_of(text))
        seq = value.pop("seq", None)
        if not in_place(seq, self.expected):
            return _Damaged("a record out of its place: one dropped, moved or added")
        self.expected = seq + 1
        return value


def _frame_of(record) -> tuple:
    """A record's (bytes, time, direction); (None, None, None) for one that carries none."""
    try:
        data = bytes.fromhex(record["hex"])
    except (ValueError, KeyError, TypeError, IndexError):
        return None, None, None  # a note, a summary, no JSON object: no bytes
    t_s = record.get("t")
    direction = record.get("dir")
    return (data, float(t_s) if isinstance(t_s, (int, float)) and not isinstance(t_s, bool) else None,
            direction if direction in DIRECTIONS else None)


def _timed(chunks: list[Chunk], marks: deque, direction: str | None) -> Iterator[Decoded]:
    for chunk in chunks:
        while len(marks) > 1 and marks[1][0] <= chunk.offset:
            marks.popleft()
        yield Decoded(chunk, marks[0][1] if marks else None, direction)
