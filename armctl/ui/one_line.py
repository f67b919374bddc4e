"""``armctl move`` and ``armctl home``: one line run as a job through the Python API, and its summary.

Strategy: the command line's ``WORD=VALUE`` words become ``Arm.move``'s keywords (``move_words``:
a word that is not one is a usage error, nothing opened); ``Arm.open`` and the one call do the
job — the same checks, streamer and proof of rest as ``armctl run`` — and this module prints
where the arm ended, or the ``RunResult`` as JSON, and exits with the result's code.  Ctrl-C
(SIGTERM, SIGHUP) during the move is ``Arm.stop()``, as ``run``'s: said at once, the result printed.
"""
from __future__ import annotations

import json
import sys

import click

from ..errors import EXIT_PROBLEMS

API_LOGGER = "armctl.host.api"  # where Arm.move's job tells its warnings and notes (host/arm_worker.py)


def move_words(texts: tuple[str, ...]) -> dict:
    """``("z=200", "f=3000")`` → ``{"z": 200.0, "f": 3000.0}``: ``Arm.move``'s keywords, each
    once; a word that is not one (or not a number) is a usage error, nothing sent."""
    from ..host.api import MOVE_KEYWORDS
    from ..host.profile import unknown_key_hint

    words: dict = {}
    for text in texts:
        name, equals, value = text.partition("=")
        name = name.strip().lower()
        if not equals or name not in MOVE_KEYWORDS:
            hint = unknown_key_hint(name, MOVE_KEYWORDS) if equals else " (write WORD=VALUE, as z=200 or j1=30)"
            raise click.UsageError(f"{text!r} is not one of move's words{hint}")
        if name in words:
            raise click.UsageError(f"{name} is given twice")
        try:
            number = float(value) if name not in ("t", "h") else int(value)
        except ValueError:
            raise click.UsageError(f"{text}: {value!r} is not a {'whole ' if name in ('t', 'h') else ''}number") from None
        if number != number or number in (float("inf"), float("-inf")):
            raise click.UsageError(f"{text}: not a finite number")
        words[name] = int(number) if isinstance(number, float) and number.is_integer() else number
    if not words:
        raise click.UsageError("give at least one word: armctl move z=200 (or x=, y=, a=, b=, c=, j1=…j6=, u=, v=, s=, t=, h=, f=)")
    return words


def one_line_job(port, baud, profile_path, timeout_s, as_json, act, connect) -> None:
    """``armctl move``/``home``: open the arm, ``act(arm)`` (one line run as a job, proven at
    rest), print where the arm ended (text, or the ``RunResult`` as JSON), exit with its code.
    ``connect``: how the port is opened (``Arm.open``'s; the CLI's prints the simulator's banner)."""
    import logging

    from ..host.api import Arm
    from ..errors import ScriptError
    from ..host.jobflow import JobFailed
    from .output import quiet
    from .run_job import one_line_summary

    if not quiet():  # the line's lint warnings and the job's notes, as `armctl run` prints its own:
        logging.getLogger(API_LOGGER).setLevel(logging.INFO)  # (JobObserver's defaults log them there)
    with Arm.open(port, baud, profile_path, status_timeout_s=timeout_s, connect=connect) as arm:
        try:
            with _stop_signals(arm):
                result = act(arm)
        except ScriptError as error:
            for diagnostic in error.diagnostics:
                click.echo(diagnostic.render(), err=True)
            click.echo("nothing was sent to the arm", err=True)
            sys.exit(EXIT_PROBLEMS)
        except JobFailed as error:
            if error.result is None:
                raise
            result = error.result
        status = arm.status() if result.finished else None
    if as_json:
        click.echo(json.dumps(result.to_json()))
    else:
        click.echo(one_line_summary(result, None if status is None else status.position_mm))
    sys.exit(result.exit_code)


def _stop_signals(arm):
    """Ctrl-C (or SIGTERM, SIGHUP) is ``arm.stop()``, as in ``armctl run``: the move stops feeding,
    the abort sequence goes, the arm is waited for and the result ("interrupted", exit 130) is
    printed; a second press cuts the wait short.  Said at once: with control frames queued (H5)
    the pause acts only after the move in progress, which may last a minute."""
    import signal

    from ..host.stop_signals import stop_signals

    presses: list[int] = []

    def on_stop(signum: int) -> None:
        if not presses:
            click.echo("\narmctl: interrupted: stopping the move and waiting for the arm to come to rest … "
                       "(Ctrl-C again: stop waiting)", err=True)
        presses.append(signum)
        arm.stop(None if signum == signal.SIGINT else f"stopped by {signal.Signals(signum).name}")

    return stop_signals(on_stop)
