"""The one click parameter type for every number an ``armctl`` option takes.

Strategy: click's ``FloatRange`` compares with its bounds, and every comparison with NaN is
false, so ``--lead nan`` passes the range check and ``--timeout nan`` waits for ever; an open
upper bound lets ``--from-line 10**30`` through.  ``number(low, high)`` is the only way an
option declares a number: both bounds are required, NaN and ±inf are refused by name, and the
failure is click's usage error (exit 2, naming the option).  The tests find every numeric
option through click's own command objects and require it to be ``Bounded``.

``NamedFile`` is the type of every option naming a file armctl writes (``compile -o``, ``plot -o``,
``probe --write``, ``sim --stats``): a ``click.Path`` that refuses an empty name.
``OutputFile`` is the type of an option naming a file armctl writes as it goes (``run --log``,
``jog --log``, ``jog --record``): a named pipe (its open waits for a reader for ever) or a
directory is refused as a usage error naming the option; a character device is written through.
"""

from __future__ import annotations

import math
import os

import click


class Bounded:
    """Marks a click number type whose value is finite and inside ``[min, max]``."""

    min: float
    max: float

    def _ascii(self, value, param, ctx):
        # int() and float() also read other scripts' digits ("١٠" is 10): nobody types those on purpose
        if isinstance(value, str) and not value.isascii():
            self.fail(f"{value!r} is not a number (give {self._range()})", param, ctx)
        return value

    def _range(self) -> str:
        return f"{self.min:g}…{self.max:g}" if isinstance(self.min, float) else f"{self.min}…{self.max}"

    def _finite(self, value, param, ctx):
        if isinstance(value, float) and not math.isfinite(value):
            self.fail(f"{value!r} is not a finite number (give {self._range()})", param, ctx)
        return value


class BoundedFloat(Bounded, click.FloatRange):
    def convert(self, value, param, ctx):
        # inf is already out of range; NaN passes click's comparisons and is caught here
        return self._finite(super().convert(self._ascii(value, param, ctx), param, ctx), param, ctx)


class BoundedInt(Bounded, click.IntRange):
    def convert(self, value, param, ctx):
        return super().convert(self._ascii(value, param, ctx), param, ctx)


def number(low: float, high: float, *, whole: bool = False) -> click.ParamType:
    """A finite number from ``low`` to ``high`` (inclusive); ``whole``: an integer."""
    if not (math.isfinite(low) and math.isfinite(high) and low <= high):
        raise ValueError(f"bad bounds {low!r}…{high!r}")
    if whole:
        return BoundedInt(int(low), int(high))
    return BoundedFloat(float(low), float(high))


class NamedFile(click.Path):
    """A file an option names: an empty or blank name (``--log "$LOG"``, LOG unset) is a usage
    error, never the option left out (a job run without its journal, a plot written elsewhere);
    so is "-", standard input for a script, which would make a file named "-" (``./-`` names one),
    unless ``dash_is_stdout`` (``compile -o -``: None, standard output), and a file in a directory
    that is not there (``sim --stats`` would find out at exit, its session's counts lost)."""

    check_directory = True

    def __init__(self, *, dash_is_stdout: bool = False, **kwargs) -> None:
        super().__init__(**kwargs)
        self.dash_is_stdout = dash_is_stdout

    def convert(self, value, param, ctx):
        if isinstance(value, str) and not value.strip():
            self.fail(f"{value!r} names no file: give a path, or leave the option out", param, ctx)
        if value == "-":
            if self.dash_is_stdout:
                return None
            self.fail("'-' names no file here: write ./- for a file named -", param, ctx)
        directory = os.path.dirname(value)
        if self.check_directory and directory and not os.path.isdir(directory):  # (now, not after a session)
            self.fail(f"cannot write {value}: No such file or directory (no directory {directory})", param, ctx)
        return super().convert(value, param, ctx)


class OutputFile(NamedFile):
    """A file to write, named by an option: not a directory, not a named pipe or socket (the
    check of armctl/host/inputs.py, decided without opening it); a device such as /dev/null is fine.
    Its command opens it before anything starts and says why it cannot in its own terms (a
    ``run --json`` summary among them), so a missing directory is left to that open."""

    check_directory = False

    def __init__(self, *, writable: bool = False) -> None:
        super().__init__(dir_okay=False, writable=writable)

    def convert(self, value, param, ctx):
        from ..host.inputs import NotARegularFile, refuse_unless_regular

        path = super().convert(value, param, ctx)
        try:
            refuse_unless_regular(path, devices_ok=True)
        except NotARegularFile as error:
            self.fail(str(error), param, ctx)
        return path
