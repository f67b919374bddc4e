"""The one root of armctl's errors, and its few precise children.

Every error a user can cause ends up as one of these; the CLI turns them into a message and
an exit code, never a traceback.
"""

from __future__ import annotations


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
        first = self.diagnostics[0] if self.diagnostics else None
        super().__init__(str(first) if first else "script error")


class ProfileError(ArmctlError):
    """An arm profile that cannot be read or does not make sense."""


class ConfigError(ArmctlError):
    """A value in armctl.toml that cannot be used."""


class ResumeRefused(ArmctlError):
    """``run --resume LOG`` names another script, an edited one, or a file that is no run log: exit 2."""


class PortError(ArmctlError):
    """A serial port that cannot be opened, or that went away."""
