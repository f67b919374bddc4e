"""The one root of armctl's errors, its few precise children, and the exit code each ends with.

Every error a user can cause ends up as one of these; the CLI turns them into a message and
an exit code, never a traceback.  The exit codes are one table for every command (README: 0 ok,
1 problems, 2 usage, configuration or an unreadable input, 130 Ctrl-C, 141 the reader of our
output went away) and one rule maps an error to its code (``exit_code_for``).  This module
imports nothing, so the signal handlers installed on the program's first line can take
``EXIT_INTERRUPTED`` from here without delaying them.
"""

from __future__ import annotations


EXIT_OK, EXIT_PROBLEMS, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_BROKEN_PIPE = 0, 1, 2, 130, 141


class ArmctlError(Exception):
    """Root of every error armctl raises on purpose."""


class FieldError(ArmctlError, ValueError):
    """A command or status field is out of range, non-finite or of the wrong type."""


class FrameError(ArmctlError, ValueError):
    """Bytes that do not form a valid frame (length, head, tail or command code)."""


class ScriptError(ArmctlError):
    """A motion script has one or more errors; ``diagnostics`` holds them (all of them, or the
    first ``errors`` when a check stops early) and nothing was sent to the arm."""

    def __init__(self, diagnostics, errors: int | None = None):
        self.diagnostics = list(diagnostics)
        self.errors = len(self.diagnostics) if errors is None else errors
        first = leading_diagnostic(self.diagnostics)
        more = self.errors - 1
        tail = f" (and {more} more error{'s' if more != 1 else ''}: .diagnostics)" if first and more > 0 else ""
        super().__init__(f"{first}{tail}" if first else "script error")

    @classmethod
    def of(cls, diagnostics, errors: int) -> ScriptError:
        """The errors among ``diagnostics`` (warnings left out), ``errors`` counted in all."""
        return cls([d for d in diagnostics if d.is_error], errors=errors)


# E004 (a value nobody wrote) is often what a bad word on the same line leaves behind: a word
# that is wrong as written is the real diagnostic and leads the message
_CONSEQUENCES = frozenset({"E004"})


def leading_diagnostic(diagnostics):
    """The diagnostic an error's one-line message leads with: the first line's, a wrong word
    before a missing one (``G1 S3000`` without F: E005 S outside 500…2500, not E004 needs F)."""
    if not diagnostics:
        return None
    return min(diagnostics, key=lambda d: (d.span.line, d.code in _CONSEQUENCES, d.span.column))


class ProfileError(ArmctlError):
    """An arm profile that cannot be read or does not make sense."""


class ConfigError(ArmctlError):
    """A value in armctl.toml that cannot be used."""


class ResumeRefused(ArmctlError):
    """``run --resume LOG`` names another script, an edited one, or a file that is no run log: exit 2."""


class PortError(ArmctlError):
    """A serial port that cannot be opened, or that went away."""


class UnusableInput(ArmctlError):
    """An input armctl refuses to read (exit 2, nothing done with it)."""


class UsageFailure(ArmctlError):
    """A file that cannot be read or an option that makes no sense: exit 2."""


def exit_code_for(error: ArmctlError) -> int:
    """2 for usage, configuration, a profile or an input armctl cannot use; 1 for the rest."""
    usage = (UsageFailure, ProfileError, ConfigError, UnusableInput, ResumeRefused)
    return EXIT_USAGE if isinstance(error, usage) else EXIT_PROBLEMS
