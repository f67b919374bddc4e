"""Ctrl-C, SIGTERM and SIGHUP as one request to stop, for the commands that must end cleanly.

Strategy: a job or a probe that dies mid-way leaves the arm moving, or changed, with nobody to
say what ran.  So while one runs, the three signals that end a terminal program — Ctrl-C,
SIGTERM (a timeout, systemd, a CI cancelling) and SIGHUP (the terminal closed) — only call
``on_stop(signal number)``, and the command stops at its next safe point; the previous handlers
come back afterwards.  Signal handlers exist only in the main thread: elsewhere (the Python API,
a test's thread) nothing is installed and the caller's own stop applies.

The ``armctl`` program itself (never the library: ``import armctl`` installs nothing) takes the
three signals from its first instant (``install_for_program``, called before any heavy import):
until a command starts, a signal ends the process at once with exit 130 and no traceback (there
is nothing to undo: no port, no terminal mode, no output yet); while a command runs it is a
KeyboardInterrupt — what Ctrl-C always was — which the CLI turns into "interrupted", exit 130,
and which the commands that hold something (a terminal, a bridge) catch to put it back.
SIGTERM and SIGHUP thus mean Ctrl-C everywhere, before ``stop_signals`` and after it.
"""

from __future__ import annotations

import signal
import sys
import threading
from contextlib import contextmanager

from ..errors import EXIT_INTERRUPTED

TYPE_CHECKING = False  # typing's import costs milliseconds at start-up, before the handlers below
if TYPE_CHECKING:
    from typing import Callable, Iterator

STOP_SIGNALS = tuple([signal.SIGINT] + [getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)])

_command_running = False  # the program's phase: set by the CLI around a command (``command_running``)


@contextmanager
def stop_signals(on_stop: Callable[[int], None]) -> Iterator[None]:
    """While inside, each of ``STOP_SIGNALS`` calls ``on_stop(signum)`` (it may raise
    ``KeyboardInterrupt`` to stop at once, e.g. on a second press)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {number: signal.getsignal(number) for number in STOP_SIGNALS}
    for number in STOP_SIGNALS:
        signal.signal(number, lambda signum, _frame: on_stop(signum))
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


def _program_stop(_signum, _frame) -> None:
    if _command_running:
        raise KeyboardInterrupt  # the command's own clean-up runs; the CLI says "interrupted", exit 130
    raise SystemExit(EXIT_INTERRUPTED)  # start-up or teardown: nothing to undo, no traceback


def install_for_program() -> None:
    """The ``armctl`` program's handlers for ``STOP_SIGNALS`` (see the module's docstring).
    Called once, first thing, by the program's entry point; the library never calls it."""
    for number in STOP_SIGNALS:
        signal.signal(number, _program_stop)


def is_the_program() -> bool:
    """Whether this process is the ``armctl`` command: ``python -m armctl``, or the console
    script (a file named ``armctl``, ``armctl.exe`` or ``armctl-script.py``) that is importing
    armctl.ui.cli — not a program (a test runner, a user's script) that imports the package."""
    import os

    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    if spec is not None:
        return spec.name == "armctl.__main__"
    name = os.path.basename(getattr(main, "__file__", None) or "")
    return os.path.splitext(name)[0] in ("armctl", "armctl-script")


@contextmanager
def command_running() -> Iterator[None]:
    """Around a command of the program: a stop signal is a KeyboardInterrupt inside."""
    global _command_running
    _command_running = True
    try:
        yield
    finally:
        _command_running = False
