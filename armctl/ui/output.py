"""How much a command says: the ``main`` group's ``-v`` and ``-q``.

Strategy: ``-v`` is ``logging`` at INFO on the ``armctl`` logger, written to stderr — the pure
core never logs; the edges that drive it (armctl/host/runner.py: why a write waited, what evidence
advanced the lower bound of frames consumed) log what the core leaves as data.  ``-q`` is one
question, ``quiet()``, that the commands ask before printing anything that is neither an error
nor their summary or data (the simulator banner, `run`'s live panel and progress lines, the
warnings of `run`'s check and of `lint`'s text and GitHub output).  Both live on the click
context of the ``main`` group, so one in-process invocation never leaks into the next.
"""

from __future__ import annotations

import logging
import sys

import click

LOGGER_NAME = "armctl"
_HANDLER_NAME = "armctl-cli"


class _StderrHandler(logging.StreamHandler):
    """Writes to whatever ``sys.stderr`` is when a record is emitted: click's test runner
    swaps it, and rich's live panel redirects it so a line lands above the panel."""

    @property
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, _value) -> None:  # StreamHandler.__init__ assigns it: the property decides
        pass


def configure(verbose: bool, quiet: bool) -> None:
    """Route the ``armctl`` loggers to stderr: INFO with ``-v``, else warnings (errors with ``-q``)."""
    logger = logging.getLogger(LOGGER_NAME)
    if not any(handler.get_name() == _HANDLER_NAME for handler in logger.handlers):
        handler = _StderrHandler()
        handler.set_name(_HANDLER_NAME)
        handler.setFormatter(logging.Formatter("armctl: %(message)s"))
        logger.addHandler(handler)
    logger.propagate = False  # one line per record, whatever the root logger does
    logger.setLevel(logging.INFO if verbose else logging.ERROR if quiet else logging.WARNING)


def quiet() -> bool:
    """``-q`` was given: print only errors, the summary and the data asked for."""
    ctx = click.get_current_context(silent=True)
    return bool(ctx is not None and ctx.find_root().params.get("quiet"))


def announce(text: str) -> None:
    """A notice on stderr (the simulator banner): not with ``-q``."""
    if not quiet():
        click.echo(text, err=True)
