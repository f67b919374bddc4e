"""Which scripts a lint run reads: files, directories searched recursively, ``-`` for stdin.

Strategy: ``expand(paths, include, exclude)`` turns the command-line arguments into a stream of
``Target``s in a stable order — a named file is always linted (whatever its extension), a
directory is walked (sorted, hidden directories such as .git and .venv skipped, symlinked
directories not followed) for files whose name matches an ``include`` pattern and no
``exclude`` pattern, ``-`` is standard input.  A path that does not exist or a directory
holding no script becomes a ``Target`` with a ``problem`` instead of an exception, so the
command reports it in order and still lints the rest.  Patterns come from ``[lint]`` in
armctl.toml (``include``, ``exclude``); defaults below.  Only this module (and command.py)
touches the file system.
"""

from __future__ import annotations

import fnmatch
import os
from dataclasses import dataclass
from typing import Iterable, Iterator, Optional

DEFAULT_INCLUDE = ("*.txt", "*.arm", "*.gcode", "*.nc")
STDIN = "-"


@dataclass(frozen=True)
class Target:
    """One script to lint (``path``; ``-`` is stdin), or a ``problem`` with an argument."""

    path: str
    problem: Optional[str] = None

    @property
    def is_stdin(self) -> bool:
        return self.path == STDIN and self.problem is None


def expand(paths: Iterable[str], include: Iterable[str] = DEFAULT_INCLUDE, exclude: Iterable[str] = ()) -> Iterator[Target]:
    include, exclude = tuple(include), tuple(exclude)
    seen: set[str] = set()
    for path in paths:
        if path == STDIN:
            yield Target(STDIN)
        elif os.path.isdir(path):
            found = False
            for target in _walk(path, include, exclude):
                found = True
                if target.problem is not None or _first_time(target.path, seen):
                    yield target
            if not found:
                yield Target(path, f"{path}: no motion scripts here ({' '.join(include)}, searched recursively)")
        elif os.path.exists(path) or os.path.islink(path):
            if _first_time(path, seen):
                yield Target(path)
        else:
            yield Target(path, f"{path}: no such file or directory")


def _first_time(path: str, seen: set[str]) -> bool:
    key = os.path.normcase(os.path.abspath(path))
    if key in seen:
        return False
    seen.add(key)
    return True


def _walk(root: str, include: tuple[str, ...], exclude: tuple[str, ...]) -> Iterator[Target]:
    """The scripts below ``root``, and a problem for each directory that cannot be listed (os.walk
    would pass over it: its scripts unchecked, nothing said)."""
    unreadable: list[OSError] = []
    for directory, subdirectories, files in os.walk(root, onerror=unreadable.append):
        yield from _problems(unreadable)
        subdirectories[:] = sorted(d for d in subdirectories if not d.startswith(".") and not _excluded(
            os.path.relpath(os.path.join(directory, d), root), d, exclude))
        for name in sorted(files):
            path = os.path.join(directory, name)
            relative = os.path.relpath(path, root)
            if _matches(name, include) and not _excluded(relative, name, exclude) and os.path.isfile(path):
                yield Target(path)
    yield from _problems(unreadable)


def _problems(errors: list[OSError]) -> Iterator[Target]:
    for error in errors:
        yield Target(error.filename, f"cannot read {error.filename}: {error.strerror or error}")
    errors.clear()


def _matches(name: str, patterns: tuple[str, ...]) -> bool:
    """Case-insensitive on every platform: JOB.GCODE is a script too."""
    return any(fnmatch.fnmatchcase(name.lower(), pattern.lower()) for pattern in patterns)


def _excluded(relative: str, name: str, patterns: tuple[str, ...]) -> bool:
    relative = relative.replace(os.sep, "/")
    return any(fnmatch.fnmatch(name, p) or fnmatch.fnmatch(relative, p) for p in patterns)
