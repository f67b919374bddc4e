"""The one host driver: an engine's actions carried out on an open ``Link``.

Strategy (sans-I/O, after h11): an engine — the job (armctl/core/job.py, hosted by
armctl/host/runner.py), the probe (armctl/probe/plan.py, hosted by armctl/probe/host.py) — is pure:
it answers ``next_action(now)`` with ``Write | Wait | Done`` (armctl/core/actions.py) and takes
status frames and write completions.  The driver owns the port and the clock, in one loop: ask
the engine, then write (``Link.write``), wait (``Link.wait``: on a wall clock until that time or
the next status frame the reader thread hands on; on a virtual clock a jump from burst to burst,
on past every frame the host's ``news`` says cannot change the next action) or stop.  What a
host adds around that — Ctrl-C at the safe point between two actions, the status frames read
meanwhile, a journal record made durable before a frame goes, the panel after it, a wall
clock's poll — are the hooks of its ``Host``; a hook never carries out an action itself.
"""

from __future__ import annotations

from typing import Callable

from ..core.actions import Wait, Write


class Host:
    """What one use of the driver adds around the engine's actions; every hook does nothing here.

    ``news``: a virtual wait's receiver of status frames, ``(frames, times)`` → the place of the
    first that may change the engine's next action, or None when none may (then the wait reads
    on); None: the link's ``on_status`` takes them and any frame ends the wait."""

    news: Callable[[list, list], "int | None"] | None = None

    def now(self, clock) -> float:
        """The engine's ``now`` from the link's clock."""
        return clock()

    def turn(self) -> None:
        """Before each action: a stop asked for, the frames read meanwhile handed to the engine."""

    def writing(self, action: Write, now: float) -> bool:
        """Before ``action``'s frame goes; False: it must not (the engine is asked again)."""
        return True

    def wrote(self, action: Write, now: float) -> None:
        """After the frame went to the port (the job: ``Job.wrote``)."""

    def waiting(self, action: Wait, now: float) -> float | None:
        """The clock's reading the wait ends at (None: at the next status frame)."""
        return action.until_s

    def waited(self) -> None:
        """After a wait."""

    def done(self, action, now: float) -> None:
        """The engine ended (``Done``; a probe's None)."""


def drive(engine, link, host: Host | None = None):
    """Carry out ``engine``'s actions on ``link`` until it is done; returns its last action.
    A lost port raises the link's ``PortError`` at the next turn."""
    host = host or Host()
    clock = link.clock
    while True:
        host.turn()
        if link.error is not None:
            raise link.error
        now = host.now(clock)
        action = engine.next_action(now)
        kind = type(action)
        if kind is Write:
            if host.writing(action, now):
                link.write(action.frame)
                host.wrote(action, now)
        elif kind is Wait:
            link.wait(host.waiting(action, now), host.news)
            host.waited()
        else:
            host.done(action, now)
            return action
