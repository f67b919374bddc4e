"""The exit codes of the ``armctl`` command, and which error exits with which.

Strategy: one table for every command (README: 0 ok, 1 problems, 2 usage, configuration or an
unreadable input, 130 Ctrl-C, 141 the reader of our output went away), and one rule mapping an
``ArmctlError`` to its code (``exit_code_for``).  Ctrl-C's code is armctl/stop_signals.py's: that
module is imported first of all and must import nothing heavy.
"""

from __future__ import annotations

from .errors import ArmctlError, ConfigError, ProfileError, ResumeRefused
from .inputs import UnusableInput
from .stop_signals import EXIT_INTERRUPTED

EXIT_OK, EXIT_PROBLEMS, EXIT_USAGE, EXIT_BROKEN_PIPE = 0, 1, 2, 141
__all__ = ["EXIT_BROKEN_PIPE", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_PROBLEMS", "EXIT_USAGE", "UsageFailure",
           "exit_code_for"]


class UsageFailure(ArmctlError):
    """A file that cannot be read or an option that makes no sense: exit 2."""


def exit_code_for(error: ArmctlError) -> int:
    """2 for usage, configuration, a profile or an input armctl cannot use; 1 for the rest."""
    return EXIT_USAGE if isinstance(error, (UsageFailure, ProfileError, ConfigError, UnusableInput, ResumeRefused)) else EXIT_PROBLEMS
