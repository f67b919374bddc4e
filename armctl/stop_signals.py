"""Ctrl-C, SIGTERM and SIGHUP as one request to stop, for the commands that must end cleanly.

Strategy: a job or a probe that dies mid-way leaves the arm moving, or changed, with nobody to
say what ran.  So while one runs, the three signals that end a terminal program — Ctrl-C,
SIGTERM (a timeout, systemd, a CI cancelling) and SIGHUP (the terminal closed) — only call
``on_stop(signal number)``, and the command stops at its next safe point; the previous handlers
come back afterwards.  Signal handlers exist only in the main thread: elsewhere (the Python API,
a test's thread) nothing is installed and the caller's own stop applies.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from typing import Callable, Iterator

STOP_SIGNALS = tuple([signal.SIGINT] + [getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)])


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
