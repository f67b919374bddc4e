"""What an engine asks its host to do next: ``Write | Wait | Done`` — the one vocabulary of the
host driver (armctl/host/driver.py) and of every engine it drives (the job, the probe).

Strategy: an engine is pure (sans-I/O): it answers ``next_action(now)`` with one of these and
takes status frames and write completions; the host carries the action out and owns the port
and the clock.  Plain frozen values, nothing to import but dataclasses.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True, slots=True)
class Write:
    """Write ``frame`` now, then tell the engine (the job: ``wrote(now)``); ``statement`` is what
    it carries out (the job's Statement, the probe's Command; None for an abort frame)."""

    frame: bytes
    statement: object | None = None
    control: str | None = None  # "pause toggle" for one the user asked for (``Job.pause``/``resume``)


@dataclass(frozen=True, slots=True)
class Wait:
    """Nothing to do until ``until_s`` (None: until the next status frame) or the next status
    frame; ``ready`` (a probe step's wish): the frames may end the wait sooner, once it holds."""

    until_s: float | None
    ready: Callable[[], bool] | None = None


@dataclass(frozen=True, slots=True)
class Done:
    """The engine has ended; ``outcome`` says how (the job's ``Outcome``; None: it just ended)."""

    outcome: object = None

