"""Where armctl writes a file the user names (``compile -o``, ``run --log``): never over an input,
never half a file, and never by replacing something that is not a regular file.

Strategy: ``compile`` writes its frames to a temporary file while the script compiles and makes
them the output only after a clean check (``PendingOutput.commit``).  A regular file (or a new
one) is replaced atomically: the temporary file lives next to the real path (symlinks followed,
so a link keeps pointing where it did) and ``os.replace`` puts it there, so a reader never sees
half a file.  Anything else the path may name — a device (``/dev/null``), a FIFO, a terminal —
is written through, never replaced: replacing ``/dev/null`` with a file (as root) breaks the
machine.  ``refuse_same_file`` is the one check that an output is not the script itself (same
device and inode, through links, including a script read from stdin).  Errors carry the path
the user gave, not a temporary name.
"""

from __future__ import annotations

import os
import shutil
import stat
import sys
import tempfile


class SameFileError(ValueError):
    """The output named is the input itself; nothing was written."""


def _identity(path_or_fd) -> tuple[int, int] | None:
    try:
        info = os.fstat(path_or_fd) if isinstance(path_or_fd, int) else os.stat(path_or_fd)
    except (OSError, ValueError):
        return None
    return (info.st_dev, info.st_ino) if stat.S_ISREG(info.st_mode) else None


def refuse_same_file(output: str, script: str, option: str) -> None:
    """``SameFileError`` when ``output`` is the file ``script`` was read from (``-``: stdin)."""
    if script == "-":
        source = _identity(sys.stdin.fileno()) if _has_stdin() else None
    else:
        source = _identity(script)
    if source is not None and _identity(output) == source:
        raise SameFileError(f"refusing to write {option} {output}: it is the script itself ({script}); choose another path")


def _has_stdin() -> bool:
    try:
        sys.stdin.fileno()
        return True
    except (AttributeError, OSError, ValueError):  # replaced by a test runner, closed
        return False


def _replaceable(path: str) -> bool:
    """A regular file, or nothing yet: the output may be replaced atomically."""
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except FileNotFoundError:
        return True


class PendingOutput:
    """Output written to a temporary file; ``commit`` makes it the output, ``discard`` drops it.
    ``path`` None: standard output."""

    def __init__(self, path: str | None, binary: bool) -> None:
        self.path, self.binary = path, binary
        self.committed = False
        self._temp = None
        self._real = None if path is None else os.path.realpath(path)
        encoding = None if binary else "utf-8"
        if path is None or not _replaceable(self._real):
            self._file = tempfile.TemporaryFile("w+b" if binary else "w+", encoding=encoding)
        else:
            try:
                handle, self._temp = tempfile.mkstemp(prefix=".armctl-", suffix=".tmp", dir=os.path.dirname(self._real))
            except OSError as error:
                raise OSError(error.errno, error.strerror, path) from None
            os.fchmod(handle, _new_file_mode(self._real))  # mkstemp's 0600 is not what open() would give
            self._file = os.fdopen(handle, "wb" if binary else "w", encoding=encoding)
        self.stream = self._file

    def commit(self) -> None:
        if self._temp is not None:
            self._file.close()
            try:
                os.replace(self._temp, self._real)
            except OSError as error:
                raise OSError(error.errno, error.strerror, self.path) from None
        else:
            self._file.seek(0)
            if self.path is None:
                target = sys.stdout.buffer if self.binary else sys.stdout
                shutil.copyfileobj(self._file, target)
                target.flush()
            else:  # a device, a FIFO: written through, never replaced
                try:
                    with open(self._real, "wb" if self.binary else "w",
                              encoding=None if self.binary else "utf-8") as target:
                        shutil.copyfileobj(self._file, target)
                except OSError as error:  # (a full device: the error names no file of its own)
                    raise OSError(error.errno, error.strerror, self.path) from None
        self.committed = True

    def discard(self) -> None:
        self._file.close()
        if self._temp is not None and not self.committed:
            try:
                os.unlink(self._temp)
            except OSError:
                pass

    def __enter__(self) -> "PendingOutput":
        return self

    def __exit__(self, *exc) -> None:
        self.discard()


def _new_file_mode(path: str) -> int:
    """The mode ``path`` has (it is replaced), else what open() would create under the umask."""
    try:
        return os.stat(path).st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask
