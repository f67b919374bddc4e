"""The keys of ``armctl run``'s live panel: pause/resume, stop, feed override.

Strategy: a thread reads the terminal raw (``jog.terminal.key_input``: no echo, no line
buffering, Ctrl-C still a signal) and turns bytes into key names with jog's ``KeyDecoder``;
each key is a call on the ``armctl.Arm`` that runs the job — ``toggle_pause``,
``feed_override(±10, relative=True)``, ``stop`` (the Ctrl-C path) — which the arm's worker
carries out between two writes: the thread never touches the engine.  A key pressed when no
job runs (before the first frame, after the last) does nothing.  The terminal is restored however the block ends (``key_input``'s
``finally``); the thread ends with it.  Only a live panel on a terminal reads keys: piped,
``--no-live``, ``--json`` or ``-q`` runs read none.  ``KEYS`` is the one table the keys and the
panel's footer come from.
"""

from __future__ import annotations

import sys
import threading
import time
from contextlib import contextmanager

from ..core.feed import FEED_STEP_PERCENT


def _toggle(arm) -> None:
    arm.toggle_pause()


def _feed(steps: int):
    return lambda arm: arm.feed_override(steps * FEED_STEP_PERCENT, relative=True)


def _stop(arm) -> None:
    arm.stop()


# (key names as jog/keys.py names them, what the footer says, the call on the arm)
KEY_TABLE = (
    (("space", "p"), "pause/resume", _toggle),
    (("s", "q"), "stop (as Ctrl-C)", _stop),
    (("+", "="), f"feed +{FEED_STEP_PERCENT} %", _feed(+1)),
    (("-",), f"feed −{FEED_STEP_PERCENT} %", _feed(-1)),
)
KEYS = {name: request for names, _, request in KEY_TABLE for name in names}
FOOTER = "keys: " + " · ".join(f"{'/'.join(names)} {label}" for names, label, _ in KEY_TABLE)
READ_WAIT_S = 0.1  # how often the reader looks whether the run is over


def keys_available(stream=None) -> bool:
    """Keys are read from a terminal on stdin, where termios exists (not on Windows)."""
    stream = sys.stdin if stream is None else stream
    try:
        import termios  # noqa: F401  (only whether it exists)
    except ImportError:
        return False
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


def handle_key(name: str, arm) -> bool:
    """Carry out one key on ``arm`` (an ``armctl.Arm``); False when it means nothing here."""
    from ..errors import ArmctlError

    request = KEYS.get(name)
    if request is None:
        return False
    try:
        request(arm)
    except ArmctlError:
        pass  # no job running (yet, or any more): the key has nothing to act on
    return True


@contextmanager
def run_keys(arm, fd: int | None = None):
    """Read keys for ``arm`` while the block runs (a daemon thread); the terminal restored after."""
    from ..jog.keys import KeyDecoder
    from ..jog.terminal import TerminalGone, key_input, read_input

    fd = sys.stdin.fileno() if fd is None else fd
    done = threading.Event()

    def read() -> None:
        decoder = KeyDecoder()
        while not done.is_set():
            try:
                data = read_input(fd, READ_WAIT_S)
            except (TerminalGone, OSError):
                return
            now = time.monotonic()
            for key in decoder.feed(data, now) + decoder.expire(now):
                handle_key(key.name, arm)

    with key_input(fd):
        thread = threading.Thread(target=read, name="armctl-run-keys", daemon=True)
        thread.start()
        try:
            yield
        finally:
            done.set()
            thread.join(READ_WAIT_S * 5)
