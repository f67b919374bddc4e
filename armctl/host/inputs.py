"""Bounded reads: every input armctl takes from a file or stdin is read with one helper.

Strategy: ``read_bounded`` reads in chunks and stops one byte past a limit, so an endless
input (``/dev/zero``, ``yes |``, a FIFO nobody closes) costs at most the limit in memory and
the time to read it, and ends in ``InputTooLarge`` (the CLI's exit 2) instead of a hang or
gigabytes of memory.  Where a file is meant (a profile, armctl.toml, a ``--resume`` log, a
``decode`` input), ``read_file_bounded`` reads only a regular file: a named pipe, a device or a
directory is refused before it is opened (``open_regular``: a named pipe nobody writes to
would block the open for ever), and stdin (``-``) is the way to give a stream.  A script is
the exception (``any_file``): ``armctl run <(generator)`` is a pipe, and a device such as
``/dev/zero`` ends at its first NUL byte.  A script reader may also stop early at the first NUL byte: the compiler
stops reading a script there anyway (it is binary, E011), so nothing after it can matter.

Limits (documented in the README):
  MAX_INPUT_BYTES  128 MiB — a script, ``decode`` input, a log.  The 1,000,000-line benchmark
                   script of benchmarks/compile_speed.py is about 72 MB.
  MAX_TOML_BYTES   1 MiB — an arm profile or armctl.toml (a real one is a few kB).
  MAX_LOG_BYTES    2 GiB — a ``--resume`` log, read line by line (``read_lines_bounded``, each
                   line at most ``MAX_LINE_BYTES``): a 24-hour job's journal — its frames (the
                   2,000,000-line limit bounds them at any baud rate), a status record every 30 ms
                   and the progress records — about 7 KB/s at 9600 baud, 0.6 GB a day.
"""

from __future__ import annotations

import os
import stat
from typing import BinaryIO, Iterable, Iterator

from ..errors import UnusableInput

MAX_INPUT_BYTES = 128 * 1024 * 1024
MAX_TOML_BYTES = 1024 * 1024
MAX_LOG_BYTES = 2 * 1024 * 1024 * 1024
MAX_LINE_BYTES = 1024 * 1024  # a journal record is under 1 KB: a longer line is no log's
_CHUNK_BYTES = 1024 * 1024


class InputTooLarge(UnusableInput):
    """An input longer than armctl reads (or an endless one): exit 2, nothing done with it."""

    @classmethod
    def beyond(cls, name: str, limit_bytes: int) -> "InputTooLarge":
        return cls(f"{name}: longer than {describe_limit(limit_bytes)}: armctl reads at most that much "
                   "(is this the file you meant?)")


def describe_limit(limit_bytes: int) -> str:
    """``134217728`` → ``128 MiB``; small limits in bytes."""
    for unit, size in (("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if limit_bytes >= size and limit_bytes % size == 0:
            return f"{limit_bytes // size} {unit}"
    return f"{limit_bytes} bytes"


def read_bounded(stream: BinaryIO, name: str, limit_bytes: int = MAX_INPUT_BYTES, *, stop_at_nul_line: bool = False) -> bytes:
    """All of ``stream`` (binary), or ``InputTooLarge`` as soon as it is longer than
    ``limit_bytes``.  With ``stop_at_nul_line`` the result ends with the line holding the
    first NUL byte (or at the limit's read if that line does not end)."""
    chunks: list[bytes] = []
    total = 0
    size = _file_size(stream)  # a regular file: read it in one piece (one copy in memory, not two)
    while True:
        chunk = stream.read(min(max(_CHUNK_BYTES, size + 1), limit_bytes + 1 - total))
        if not chunk:
            break
        if stop_at_nul_line and b"\x00" in chunk:
            nul = chunk.index(b"\x00")
            end = chunk.find(b"\n", nul)
            chunks.append(chunk if end < 0 else chunk[: end + 1])
            break
        chunks.append(chunk)
        total += len(chunk)
        if total > limit_bytes:
            raise InputTooLarge.beyond(name, limit_bytes)
    return b"".join(chunks)


def read_lines_bounded(stream: BinaryIO, name: str, limit_bytes: int = MAX_LOG_BYTES) -> Iterator[bytes]:
    """``read_blocks_bounded`` as lines (``split_lines``), each at most ``MAX_LINE_BYTES``: memory
    stays bounded by a line, not the input."""
    return split_lines(read_blocks_bounded(stream, name, limit_bytes), name, MAX_LINE_BYTES)


def split_lines(blocks: Iterable[bytes], name: str = "", max_line_bytes: int | None = None) -> Iterator[bytes]:
    """``blocks`` (an input read in pieces) as lines, each with its line break (the last without
    one if the input has none); with ``max_line_bytes``, ``InputTooLarge`` for a longer line —
    but a longer run of NUL bytes alone (blocks a file system allocated and never wrote) reads
    as one NUL, which means the same."""
    tail = b""
    for block in blocks:
        lines = (tail + block).split(b"\n")
        tail = lines.pop()
        for line in lines:
            yield line + b"\n"
        if max_line_bytes is not None and len(tail) > max_line_bytes:
            if not tail.strip(b"\0"):
                tail = b"\0"
                continue
            raise InputTooLarge(f"{name}: a line longer than {describe_limit(max_line_bytes)}: armctl reads no longer "
                                "line there (is this the file you meant?)")
    if tail:
        yield tail


def read_blocks_bounded(stream: BinaryIO, name: str, limit_bytes: int = MAX_INPUT_BYTES,
                        block_bytes: int = _CHUNK_BYTES) -> Iterator[bytes]:
    """``read_bounded`` for a reader that streams (``armctl decode``): ``stream`` in blocks of at
    most ``block_bytes``, and ``InputTooLarge`` as soon as it is longer than ``limit_bytes`` — at
    once, before any block, for a regular file already that long (nothing printed for it)."""
    if _file_size(stream) > limit_bytes:
        raise InputTooLarge.beyond(name, limit_bytes)
    total = 0
    while True:
        block = stream.read(block_bytes)
        if not block:
            return
        total += len(block)
        if total > limit_bytes:
            raise InputTooLarge.beyond(name, limit_bytes)
        yield block


def _file_size(stream) -> int:
    """The size of a regular file behind ``stream``; 0 for a pipe, a device or no file."""
    try:
        info = os.fstat(stream.fileno())
    except (AttributeError, OSError, ValueError):  # io.BytesIO, a closed or unusual stream
        return 0
    return info.st_size if stat.S_ISREG(info.st_mode) else 0


class NotARegularFile(UnusableInput):
    """A path that names a named pipe, a device, a directory or a socket where a file is meant."""


_KINDS = ((stat.S_ISFIFO, "a named pipe"), (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISDIR, "a directory"), (stat.S_ISSOCK, "a socket"))


def _kind(mode: int) -> str | None:
    """What a non-regular file is, in words; None for a regular file."""
    if stat.S_ISREG(mode):
        return None
    return next((words for test, words in _KINDS if test(mode)), "not a regular file")


def kind_of(mode: int) -> str:
    """A file's kind in words, from its ``st_mode``: "a regular file", "a named pipe", …"""
    return _kind(mode) or "a regular file"


def refuse_unless_regular(path, name: str | None = None, *, devices_ok: bool = False) -> None:
    """``NotARegularFile`` unless ``path`` names a regular file (through symlinks), decided
    without opening it: opening a named pipe waits for a writer (or a reader) for ever, and
    opening a serial device may reset the board behind it.  ``devices_ok``: a character device
    passes too (an output written through: ``--log /dev/null``).  A path that does not exist
    passes (the caller's open or create says so); a path with a NUL character is refused."""
    shown = name or os.fspath(path)
    try:
        info = os.stat(path)
    except ValueError:  # embedded null byte (from a TOML string or a %00 in a URL)
        raise NotARegularFile(f"{shown}: a path with a NUL character cannot name a file") from None
    except OSError:
        return
    kind = _kind(info.st_mode)
    if kind is not None and not (devices_ok and stat.S_ISCHR(info.st_mode)):
        raise NotARegularFile(f"{shown}: {kind}, not a regular file")


def open_regular(path, name: str | None = None) -> BinaryIO:
    """``path`` opened for reading (binary) if it is a regular file; ``NotARegularFile`` (not
    opened) for anything else; OSError (missing, no permission) as the caller's to report.
    Checked before the open, and again on what was opened — without blocking (O_NONBLOCK),
    in case the path was swapped for a named pipe in between."""
    refuse_unless_regular(path, name)
    handle = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    try:
        kind = _kind(os.fstat(handle).st_mode)
        if kind is not None:
            raise NotARegularFile(f"{name or os.fspath(path)}: {kind}, not a regular file")
        if hasattr(os, "set_blocking"):
            os.set_blocking(handle, True)
        return os.fdopen(handle, "rb")
    except BaseException:
        os.close(handle)
        raise


def read_file_bounded(path: str, name: str | None = None, limit_bytes: int = MAX_INPUT_BYTES, *,
                      stop_at_nul_line: bool = False, any_file: bool = False) -> bytes:
    """``read_bounded`` on the regular file at ``path`` (``open_regular``: a named pipe, device
    or directory is ``NotARegularFile``); ``any_file``: anything ``open`` reads (a script: a
    ``<(generator)``, ``/dev/stdin``).  OSError as the caller's to report."""
    shown = name or str(path)
    with (open(path, "rb") if any_file else open_regular(path, shown)) as stream:
        return read_bounded(stream, shown, limit_bytes, stop_at_nul_line=stop_at_nul_line)
