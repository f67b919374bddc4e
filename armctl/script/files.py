"""Read a script safely and once: one immutable snapshot that every pass compiles.

Strategy: ``read_script`` reads the whole input (a file or stdin) once, with the bounded read
of armctl/host/inputs.py, into a ``ScriptSnapshot`` — an immutable ``bytes`` and the name to report.
Every pass a command makes (lint, the ``--from-line`` check, the estimate, the stream, the
written output, the resume-line computation) iterates ``snapshot.lines()``, and compiling is
a pure function of those lines and the initial state; so a file edited or replaced while
``run`` streams cannot change what is sent: what was checked is exactly what is sent.  The
snapshot stops at the line holding the first NUL byte (the compiler stops reading there: the
input is binary, E011), so ``/dev/zero`` costs one chunk, not the limit.

Lines: decoded as UTF-8 with ``surrogateescape`` (undecodable bytes survive as lone
surrogates, which the compiler reports, E011, with their column).  A line longer than the
cap is cut (the rest is skipped) and yielded as a ``CutLine`` that knows its full length in
characters, so E011 can say how long it really was.  A UTF-8 byte-order mark on the first line
is dropped.  ``iter_lines``/``compile_file`` still stream a file in flat memory for the
library API (benchmarks/compile_speed.py); they are bounded by the same limit.
"""

from __future__ import annotations

import io
import os
import sys
from typing import BinaryIO, Iterator, Union

from ..host.inputs import MAX_INPUT_BYTES, InputTooLarge, read_bounded, read_file_bounded
from ..core.records import record
from .compiler import MAX_LINE_LENGTH, Compilation, compile_lines
from .modal import InitialState

# Bytes read per line at most: a cut line still decodes to more than MAX_LINE_LENGTH characters
# (a character is at most 4 bytes), so the compiler reports it as too long.
MAX_LINE_BYTES = 4 * MAX_LINE_LENGTH + 4
_CONTINUATION_BYTES = bytes(range(0x80, 0xC0))  # UTF-8 bytes that do not start a character


class CutLine(str):
    """A line cut at ``MAX_LINE_BYTES``; ``length`` is the whole line's length in characters
    (UTF-8 lead bytes and undecodable bytes, each one character), without its line ending."""

    length: int


def _characters(raw: bytes) -> int:
    return len(raw.translate(None, _CONTINUATION_BYTES))


def iter_lines(stream: BinaryIO, limit_bytes: int = MAX_INPUT_BYTES, name: str = "<script>") -> Iterator[str]:
    """Decoded lines (with their line endings) from a binary stream, each at most
    ``MAX_LINE_BYTES`` long; ``InputTooLarge`` past ``limit_bytes`` in all."""
    first = True
    total = 0
    while True:
        raw = stream.readline(MAX_LINE_BYTES)
        if not raw:
            return
        total += len(raw)
        cut = None
        if len(raw) == MAX_LINE_BYTES and not raw.endswith(b"\n") and b"\x00" not in raw:
            cut = _characters(raw)  # a NUL line is binary: the compiler stops there anyway
            while True:  # skip the rest of an over-long line, counting its characters
                rest = stream.readline(65536)
                total += len(rest)
                if total > limit_bytes:
                    break
                cut += _characters(rest.rstrip(b"\r\n"))
                if not rest or rest.endswith(b"\n"):
                    break
        if total > limit_bytes:
            raise InputTooLarge.beyond(name, limit_bytes)
        if first:
            first = False
            if raw.startswith(b"\xef\xbb\xbf"):
                raw = raw[3:]
                cut = None if cut is None else cut - 1
        text = raw.decode("utf-8", "surrogateescape")
        if cut is not None:
            text = CutLine(text)
            text.length = cut
        yield text


def read_lines(path: Union[str, os.PathLike]) -> Iterator[str]:
    """The lines of the script at ``path`` (see ``iter_lines``); the file closes at the end."""
    with open(path, "rb") as stream:
        yield from iter_lines(stream, name=os.fspath(path))


def compile_file(path: Union[str, os.PathLike], initial: InitialState | None = None, **options) -> Compilation:
    """Compile the script at ``path`` as a stream; diagnostics name the file as given."""
    return compile_lines(read_lines(path), os.fspath(path), initial, **options)


@record
class ScriptSnapshot:
    """A script's bytes as read once; every pass over it sees exactly the same lines."""

    name: str
    data: bytes

    def lines(self) -> Iterator[str]:
        """A fresh iterator over the same lines (see ``iter_lines``)."""
        return iter_lines(io.BytesIO(self.data), len(self.data), self.name)

    def compile(self, initial: InitialState | None = None, **options) -> Compilation:
        """A fresh compilation of the snapshot (deterministic: same lines, same initial state)."""
        return compile_lines(self.lines(), self.name, initial, **options)


def read_script(path: str, limit_bytes: int = MAX_INPUT_BYTES, stdin: BinaryIO | None = None) -> ScriptSnapshot:
    """Read the script at ``path`` (``-``: standard input, named ``<stdin>``) once, bounded;
    OSError and ``InputTooLarge`` are the caller's to report."""
    if path == "-":
        stream = stdin if stdin is not None else sys.stdin.buffer
        return ScriptSnapshot("<stdin>", read_bounded(stream, "<stdin>", limit_bytes, stop_at_nul_line=True))
    return ScriptSnapshot(path, read_file_bounded(path, path, limit_bytes, stop_at_nul_line=True, any_file=True))
