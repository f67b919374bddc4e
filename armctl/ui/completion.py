"""``armctl completion bash|zsh|fish``: print the shell's completion script.

Strategy: no completion logic of our own.  click already completes every command, option and
choice when the shell calls ``armctl`` with ``_ARMCTL_COMPLETE=bash_complete`` (or zsh/fish)
set; this command only prints the script that makes the shell do so — the very text click
prints for ``_ARMCTL_COMPLETE=bash_source armctl`` — through ``click.shell_completion``'s own
classes, so it stays in step with the installed click.  The script is always for the installed
command ``armctl`` (also when this runs as ``python -m armctl``), since that is the name the
shell completes.  Only click is imported; armctl/ui/cli.py registers ``completion`` with
``main.add_command(completion)``.

Exit codes: 0 the script was printed, 2 a shell click cannot complete for (a usage error).

The shell's request itself (``COMP_WORDS``, ``COMP_CWORD``) is click's to read; one it cannot read
(``COMP_CWORD=abc``, a variable unset, a word that is not UTF-8) is a usage error here
(``request_errors``: one line, exit 2), where click would raise a traceback.
"""

from __future__ import annotations

import os
from contextlib import contextmanager

import click

from ..errors import UsageFailure

PROG_NAME = "armctl"  # the console script in pyproject.toml's [project.scripts]
SHELLS = ("bash", "zsh", "fish", "powershell")  # powershell: click 8.5's PowerShellComplete


def complete_var(prog_name: str = PROG_NAME) -> str:
    """The environment variable click's completion listens to: ``_ARMCTL_COMPLETE`` (click
    derives it from the program name in the same way when no ``complete_var`` is given)."""
    return f"_{prog_name}_COMPLETE".replace("-", "_").upper()


@click.command(name="completion")
@click.argument("shell", type=click.Choice(SHELLS))
@click.pass_context
def completion(ctx: click.Context, shell: str):
    """Print the completion script for SHELL (bash, zsh, fish or powershell).

    \b
    bash:  eval "$(armctl completion bash)"   in ~/.bashrc (bash 4.4 or later)
    zsh:   eval "$(armctl completion zsh)"    in ~/.zshrc
    fish:  armctl completion fish > ~/.config/fish/completions/armctl.fish
    powershell:  armctl completion powershell | Out-String | Invoke-Expression   in $PROFILE
    """
    from click.shell_completion import get_completion_class

    completer = get_completion_class(shell)  # never None: SHELLS are click's built-in shells
    root = ctx.find_root().command  # the whole `armctl` group, so every command completes
    click.echo(completer(root, {}, PROG_NAME, complete_var()).source(), nl=False)  # as click prints it


@contextmanager
def request_errors(variable: str):
    """Click answering the shell's request (``variable``: ``_ARMCTL_COMPLETE``, whose value names
    the shell): what it raises on a request it cannot read — ``int("abc")``, ``os.environ["COMP_CWORD"]``
    unset, fish's blank word, an answer that is not UTF-8 — as a ``UsageFailure`` naming it."""
    try:
        yield
    except UnicodeEncodeError:  # click encodes its answer strictly; a file name's bytes need not be UTF-8
        raise UsageFailure("shell completion: the word to complete is not UTF-8 text, which click cannot "
                           "answer for") from None
    except (KeyError, ValueError, IndexError):
        raise UsageFailure(f"shell completion: {_request_problem(os.environ, variable)}") from None


def _request_problem(environ, variable: str) -> str:
    from ..core.toml_reading import short_repr

    for name in ("COMP_WORDS", "COMP_CWORD"):
        if name not in environ:
            return f"{name} is not set ({variable} asks for an answer to COMP_WORDS and COMP_CWORD, as the " \
                   "script of `armctl completion SHELL` sets them)"
    shell = environ.get(variable, "").partition("_")[0]
    wanted = "the word to complete" if shell == "fish" else "the index of the word to complete, a whole number"
    return f"COMP_CWORD={short_repr(environ['COMP_CWORD'])} is not {wanted}"
