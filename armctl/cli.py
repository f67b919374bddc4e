"""The ``armctl`` command: click wiring and nothing else.

Strategy: each command parses its options, calls into the package and maps the outcome to an
exit code.  Heavy modules (lark, rich, serial) are imported inside the command that needs
them, so ``armctl --help`` stays fast.  Every error a user can cause is an ``ArmctlError`` or
an ``OSError`` and becomes one line on stderr with an exit code — never a traceback.

Exit codes: 0 success, 1 the input had problems (script errors, lint findings, a job that did
not finish), 2 usage errors and unreadable files, 130 interrupted by Ctrl-C.
"""

from __future__ import annotations

import sys

import click

from . import __version__
from .errors import ArmctlError

EXIT_OK, EXIT_PROBLEMS, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


class UsageFailure(ArmctlError):
    """A file that cannot be read or an option that makes no sense: exit 2."""


class ArmctlGroup(click.Group):
    """Turns the errors a user can cause into a message and an exit code."""

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except UsageFailure as error:
            _fail(str(error), EXIT_USAGE)
        except ArmctlError as error:
            _fail(str(error), EXIT_PROBLEMS)
        except KeyboardInterrupt:
            _fail("interrupted", EXIT_INTERRUPTED)
        except OSError as error:
            _fail(_os_error_text(error), EXIT_USAGE)


def _fail(message: str, code: int):
    click.echo(f"armctl: {message}", err=True)
    sys.exit(code)


def _os_error_text(error: OSError) -> str:
    name = f"{error.filename}: " if error.filename else ""
    return f"{name}{error.strerror or error}"


@click.group(cls=ArmctlGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, "--version", prog_name="armctl")
def main():
    """Drive a 6-axis desktop robot arm over its serial connector.

    Without --port (or ARMCTL_PORT, or `port` in armctl.toml) commands talk to the built-in
    simulator.
    """


def _read_input(path: str) -> bytes:
    if path == "-":
        return click.get_binary_stream("stdin").read()
    try:
        with open(path, "rb") as handle:
            return handle.read()
    except OSError as error:
        raise UsageFailure(f"cannot read {path}: {error.strerror}") from None


@main.command()
@click.argument("source", default="-", metavar="[FILE|-]")
def decode(source: str):
    """Name every frame in hex text, raw bytes or an armctl log.

    Finds 48-byte command frames and 9-byte status frames in any mix, prints one readable
    line per frame (offset, family, command and fields with units) and marks bytes that
    belong to no frame.
    """
    from .formats import bytes_from_input, describe_chunk, summary_line
    from .protocol import scan_frames

    data = bytes_from_input(_read_input(source))
    chunks = list(scan_frames(data))
    for chunk in chunks:
        click.echo(describe_chunk(chunk))
    click.echo(summary_line(chunks), err=True)
