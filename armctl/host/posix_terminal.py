"""Which commands need a POSIX terminal, said in one place, with a message instead of a traceback.

Strategy: two features rest on the POSIX terminal interface — ``jog`` reads raw key presses
(termios raw mode, ``select`` on stdin, SIGHUP) and ``sim --pty`` makes a pseudo-terminal
(``os.openpty``, ``tty``, termios).  Where Python has no ``termios`` module (Windows; WSL is
Linux and has it) neither can work, and importing their modules would end in a
ModuleNotFoundError traceback.  So each calls ``require_posix_terminal`` before it opens
anything, and the modules that use termios import it only after that call.  The error is a
``ConfigError`` (this machine cannot do what was asked: exit 2, like any usage or
configuration error) that names the command and what works instead.  Every other command
uses only pyserial, sockets and rich, and runs on Windows too.
"""

from __future__ import annotations

import sys

from ..errors import ConfigError


class NeedsPosixTerminal(ConfigError):
    """The command needs termios (a POSIX terminal) and this Python has none."""


def require_posix_terminal(command: str, instead: str) -> None:
    """Raise ``NeedsPosixTerminal`` unless termios can be imported.  ``command`` is what the
    user typed (``armctl jog``); ``instead`` is what to do on this machine."""
    try:
        import termios  # noqa: F401  (only whether it exists)
    except ImportError:
        raise NeedsPosixTerminal(
            f"{command} needs a POSIX terminal (Linux, macOS, or WSL on Windows), and this Python "
            f"({sys.platform}) has no termios module: {instead}") from None
