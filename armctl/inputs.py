"""Bounded reads: every input armctl takes from a file or stdin is read with one helper.

Strategy: ``read_bounded`` reads in chunks and stops one byte past a limit, so an endless
input (``/dev/zero``, ``yes |``, a FIFO nobody closes) costs at most the limit in memory and
the time to read it, and ends in ``InputTooLarge`` (the CLI's exit 2) instead of a hang or
gigabytes of memory.  A script reader may also stop early at the first NUL byte: the compiler
stops reading a script there anyway (it is binary, E011), so nothing after it can matter.

Limits (documented in the README):
  MAX_INPUT_BYTES  128 MiB — a script, ``decode`` input, a log.  The 1,000,000-line benchmark
                   script of benchmarks/compile_speed.py is about 72 MB.
  MAX_TOML_BYTES   1 MiB — an arm profile or armctl.toml (a real one is a few kB).
"""

from __future__ import annotations

from typing import BinaryIO

from .errors import ArmctlError

MAX_INPUT_BYTES = 128 * 1024 * 1024
MAX_TOML_BYTES = 1024 * 1024
_CHUNK_BYTES = 1024 * 1024


class InputTooLarge(ArmctlError):
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


def _file_size(stream) -> int:
    """The size of a regular file behind ``stream``; 0 for a pipe, a device or no file."""
    import os
    import stat

    try:
        info = os.fstat(stream.fileno())
    except (AttributeError, OSError, ValueError):  # io.BytesIO, a closed or unusual stream
        return 0
    return info.st_size if stat.S_ISREG(info.st_mode) else 0


def read_file_bounded(path: str, name: str | None = None, limit_bytes: int = MAX_INPUT_BYTES, *,
                      stop_at_nul_line: bool = False) -> bytes:
    """``read_bounded`` on the file at ``path``; OSError as the caller's to report."""
    with open(path, "rb") as stream:
        return read_bounded(stream, name or str(path), limit_bytes, stop_at_nul_line=stop_at_nul_line)
