"""Read a script file as lines of text, safely, for the compiler.

Strategy: the file is read in binary, one line at a time with a length cap, and each line is
decoded as UTF-8 with ``surrogateescape``: undecodable bytes survive as lone surrogates, which
the compiler reports (E011) with their column instead of failing the whole file.  A line
longer than the cap is cut (the rest of it is skipped, never held in memory) and reported as
too long.  A UTF-8 byte-order mark on the first line is dropped.
"""

from __future__ import annotations

import os
from typing import BinaryIO, Iterator, Union

from .compiler import MAX_LINE_LENGTH, Compilation, compile_lines
from .modal import InitialState

# Bytes read per line at most: a cut line still decodes to more than MAX_LINE_LENGTH characters
# (a character is at most 4 bytes), so the compiler reports it as too long.
MAX_LINE_BYTES = 4 * MAX_LINE_LENGTH + 4


def iter_lines(stream: BinaryIO) -> Iterator[str]:
    """Decoded lines (with their line endings) from a binary stream, each at most
    ``MAX_LINE_BYTES`` long."""
    first = True
    while True:
        raw = stream.readline(MAX_LINE_BYTES)
        if not raw:
            return
        if len(raw) == MAX_LINE_BYTES and not raw.endswith(b"\n"):
            while True:  # skip the rest of an over-long line
                rest = stream.readline(65536)
                if not rest or rest.endswith(b"\n"):
                    break
        if first:
            first = False
            if raw.startswith(b"\xef\xbb\xbf"):
                raw = raw[3:]
        yield raw.decode("utf-8", "surrogateescape")


def read_lines(path: Union[str, os.PathLike]) -> Iterator[str]:
    """The lines of the script at ``path`` (see ``iter_lines``); the file closes at the end."""
    with open(path, "rb") as stream:
        yield from iter_lines(stream)


def compile_file(path: Union[str, os.PathLike], initial: InitialState | None = None, **options) -> Compilation:
    """Compile the script at ``path`` as a stream; diagnostics name the file as given."""
    return compile_lines(read_lines(path), os.fspath(path), initial, **options)
