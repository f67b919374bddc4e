"""The terminal edge: raw keyboard input, and the terminal restored on every way out.

Strategy: ``raw_terminal(fd)`` is a context manager that saves the terminal's attributes, sets
raw input — no echo, no line buffering, no signals from keys (so Ctrl-C arrives as byte 3 and
is handled like any key, after the neutral frame), no CR→NL translation — while keeping output
processing on (rich's newlines still return the carriage), and restores the saved attributes in
``finally``.  SIGTERM and SIGHUP are turned into a ``Terminated`` exception for as long as it
is active, so a ``kill`` or a closed terminal window unwinds through the same ``finally``
blocks (neutral frame, then the terminal) as a key does.  ``read_input`` waits with ``select``
and reports a vanished terminal (end of file, EIO) as ``TerminalGone``.
"""

from __future__ import annotations

import errno
import os
import select
import signal
import termios
from contextlib import contextmanager

from ..errors import ArmctlError

READ_CHUNK = 1024
CAUGHT_SIGNALS = (signal.SIGTERM, signal.SIGHUP)


class TerminalGone(ArmctlError):
    """The terminal went away (hang-up, end of input)."""


class Terminated(ArmctlError):
    """A SIGTERM or SIGHUP arrived."""


def _raw_attributes(attributes: list) -> list:
    mode = [list(a) if isinstance(a, list) else a for a in attributes]
    iflag, oflag, cflag, lflag = 0, 1, 2, 3
    mode[iflag] &= ~(termios.BRKINT | termios.ICRNL | termios.INPCK | termios.ISTRIP | termios.IXON)
    mode[cflag] = (mode[cflag] & ~(termios.CSIZE | termios.PARENB)) | termios.CS8
    mode[lflag] &= ~(termios.ECHO | termios.ICANON | termios.IEXTEN | termios.ISIG)
    mode[6][termios.VMIN] = 1
    mode[6][termios.VTIME] = 0
    return mode


@contextmanager
def _raw_mode(fd: int, keys_signal: bool, when: int):
    """Raw input on ``fd`` inside the block (``keys_signal``: Ctrl-C still raises SIGINT); the
    saved attributes back in ``finally``, however the block ends."""
    saved = termios.tcgetattr(fd)
    mode = _raw_attributes(saved)
    if keys_signal:
        mode[3] |= termios.ISIG  # lflag
    try:
        termios.tcsetattr(fd, when, mode)
        yield
    finally:
        try:
            termios.tcsetattr(fd, termios.TCSADRAIN, saved)
        except (termios.error, OSError):
            pass  # the terminal is gone: nothing left to restore


@contextmanager
def raw_terminal(fd: int):
    """Raw keyboard input on ``fd`` inside the block; the terminal as it was afterwards."""
    raised = []

    def on_signal(number, frame):
        if not raised:  # raise once; a second signal during clean-up must not interrupt it
            raised.append(number)
            raise Terminated(f"terminated by {signal.Signals(number).name}")

    previous = {number: signal.signal(number, on_signal) for number in CAUGHT_SIGNALS}
    try:
        with _raw_mode(fd, keys_signal=False, when=termios.TCSAFLUSH):  # TCSAFLUSH drops keys typed before
            yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


@contextmanager
def key_input(fd: int):
    """Raw key input on ``fd`` for a program whose signals stay its own (``armctl run``'s
    panel): like ``raw_terminal`` but Ctrl-C still raises SIGINT (the job's Ctrl-C path) and no
    signal handler is touched; the terminal as it was afterwards, however the block ends."""
    with _raw_mode(fd, keys_signal=True, when=termios.TCSANOW):
        yield


def read_input(fd: int, timeout_s: float) -> bytes:
    """Bytes typed within ``timeout_s`` (b"" if none); ``TerminalGone`` when input ended."""
    ready, _, _ = select.select([fd], [], [], max(timeout_s, 0.0))
    if not ready:
        return b""
    try:
        data = os.read(fd, READ_CHUNK)
    except OSError as error:
        if error.errno in (errno.EIO, errno.EBADF, errno.ENXIO):
            raise TerminalGone("the terminal went away") from None
        raise
    if not data:
        raise TerminalGone("the terminal closed its input")
    return data
