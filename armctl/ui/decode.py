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
a chunk's ``offset`` counts the bytes of its own direction.  A log line that is no JSON object
with a ``hex`` string carries no bytes (a note, a progress record, a torn line), and neither
does a sealed record (``run --log``'s: place and CRC-32) whose checksum does not match: its
bytes may not be the ones written, so the CLI names its line and exits 1.

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
    DIRECTIONS, HEX_DIGIT_BYTES, WHITESPACE_BYTES, looks_like_hex, looks_like_log,
)
from ..host.inputs import MAX_INPUT_BYTES, read_blocks_bounded, split_lines
from ..core.joblog import intact
from ..core.protocol import CONTROL_HEAD, FRAME_SIZE, MOTION_HEAD, STATUS_HEAD, STATUS_SIZE
from ..core.status_frames import Chunk, chunk_at

PROBE_BYTES = 1 << 16  # an input up to this size is judged whole, as before streaming
BLOCK_BYTES = 1 << 16
JUNK_PIECE_BYTES = 1 << 16  # a longer run of stray bytes comes out in pieces of this size

_COMMAND_HEADS = frozenset((MOTION_HEAD, CONTROL_HEAD))
_HEADS = _COMMAND_HEADS | {STATUS_HEAD}
_NEXT_HEAD = re.compile(b"[" + re.escape(bytes(sorted(_HEADS))) + b"]")


class NotHex(Exception):
    """Hex text (judged on its first block) with a byte that is not a hex digit later on."""


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
                  damaged: list[int] | None = None, jobs: list | None = None) -> Iterator[Decoded]:
    """Every chunk of ``stream`` in order (``InputTooLarge`` past ``limit_bytes``, ``NotHex``
    for hex text that stops being hex beyond its first block); a log's sealed records whose
    checksum does not match give no bytes, their line numbers appended to ``damaged``; its
    intact job records (which script, from which line, on which port) go to ``jobs`` as
    (line number, record)."""
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
    offset = 0
    for block in _chain(first, rest):
        text = block.decode("ascii", "replace")
        digits = pending + "".join(text.split())
        try:
            whole = len(digits) - len(digits) % 2
            yield bytes.fromhex(digits[:whole])
        except ValueError:
            bad = next(i for i, char in enumerate(text) if not (char in string.hexdigits or char.isspace()))
            raise NotHex(f"not hex text: byte {offset + bad} is {block[bad:bad + 1]!r}") from None
        pending = digits[whole:]
        offset += len(block)
    if pending:
        raise NotHex("hex text ends with half a byte (an odd count of digits)")


def _looks_like_log(first: bytes, ended: bool) -> bool:
    if ended:
        return looks_like_log(first)
    return first.lstrip()[:1] == b"{"


def _log_lines(first: bytes, rest: Iterator[bytes]) -> Iterator[bytes]:
    return split_lines(_chain(first, rest))


def _log_chunks(first: bytes, rest: Iterator[bytes], damaged: list[int], jobs: list) -> Iterator[Decoded]:
    """Each record's bytes into its direction's scanner; each chunk with the time of the
    record its first byte came in.  A sealed record (``run --log``'s: its ``crc``) whose
    checksum does not match gives no bytes: its line number goes to ``damaged``; an intact job
    record goes to ``jobs``."""
    scanners: dict[str | None, tuple[FrameScanner, deque]] = {}
    for number, line in enumerate(_log_lines(first, rest), 1):
        record = _record(line)
        if record is _DAMAGED:
            damaged.append(number)
            continue
        if record is None:
            if b'"job"' in line and (job := _job(line)) is not None:
                jobs.append((number, job))
            continue
        data, t_s, direction = record
        scanner, marks = scanners.setdefault(direction, (FrameScanner(), deque()))
        marks.append((scanner._base + len(scanner._buffer), t_s))  # where this record's bytes start
        yield from _timed(scanner.feed(data), marks, direction)
    for direction, (scanner, marks) in scanners.items():
        yield from _timed(scanner.finish(), marks, direction)


_DAMAGED = object()  # ``_record``'s answer for a sealed record whose checksum does not match


def _record(line: bytes):
    """A record's (bytes, time, direction); None for a line that carries none; ``_DAMAGED``."""
    if not line.strip():
        return None
    try:
        record = json.loads(line)
    except (ValueError, RecursionError):
        return None  # no JSON (a torn last line), nested too deep: no bytes
    if isinstance(record, dict) and "crc" in record and not intact(record):
        return _DAMAGED  # its bytes may not be the ones written (a flipped bit, in them or in a key)
    try:
        data = bytes.fromhex(record["hex"])
    except (ValueError, KeyError, TypeError):
        return None  # a note, a summary, no JSON object: no bytes
    t_s = record.get("t")
    direction = record.get("dir")
    return (data, float(t_s) if isinstance(t_s, (int, float)) and not isinstance(t_s, bool) else None,
            direction if direction in DIRECTIONS else None)


def _job(line: bytes) -> dict | None:
    """The job record on ``line`` (``run --log``'s first: script, from line, port), if intact."""
    try:
        record = json.loads(line)
    except (ValueError, RecursionError):
        return None
    if not isinstance(record, dict) or record.get("dir") != "job" or ("crc" in record and not intact(record)):
        return None
    return record


def _timed(chunks: list[Chunk], marks: deque, direction: str | None) -> Iterator[Decoded]:
    for chunk in chunks:
        while len(marks) > 1 and marks[1][0] <= chunk.offset:
            marks.popleft()
        yield Decoded(chunk, marks[0][1] if marks else None, direction)
