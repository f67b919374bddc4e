"""The rules of arm evidence, once: when the arm's reports agree, and when the arm is at rest.

Strategy: pure functions of readings and the times they were read — no state, no clock, no
port.  The status line has no checksum (PROTOCOL.md H9) and a report may be lost, so nothing
is concluded from one report, nor from the silence of a kind whose reports went missing.
Everything that concludes "the arm is paused", "the arm reads this value" or "the arm is
still" from status frames asks here and restates nothing:

- **Agreeing reports** (``AGREEING_REPORTS``, ``agreed``, ``agreeing_runs``): a value counts as
  reported once that many consecutive reports of its kind agree on it; one corrupted byte then
  never makes armctl toggle the arm or claim a value.  The job engine's pause state
  (armctl/core/job_readings.py, armctl/core/job_control.py ``pause_toggle_needed``), the start of a run
  (armctl/host/jobflow.py ``reported_pause``), the benchmark's start and the probe's readings
  (armctl/probe/plan.py ``Seen``, armctl/probe/steps.py).
- **A jump confirmed** (``reach``, ``beyond_reach``): a reading farther from the last accepted one than
  the arm can move in the time between is held back until the next report of its kind lands
  within reach of it (armctl/core/armstate.py): a real jump (after a reset) is one report late, a
  corrupted one is never taken.
- **At rest** (``REST_CHECK_S``, ``known_still_s``, ``still_long_enough``): readings unchanged
  for ``REST_CHECK_S``, *each kind re-read in that time* — the time they are known unchanged
  ends at the oldest of each kind's latest reports, not at now: a wrist turning while the
  joints 4-6 reports are lost looks still to every other kind.  The job engine's end of a job
  (armctl/core/job_readings.py) and the waits for rest before and after a resume
  (armctl/host/jobflow.py ``wait_for_rest``); the probe's stillness (armctl/probe/steps.py) takes
  its span from agreeing runs, each kind's from its own first run.
- **Motion seen** (``MotionSeen``): a kind's reports agreed on a value, then on another (a slow
  move: each step read twice), or ``DISTINCT_REPORTS`` of them in a row each read another value
  than the one agreed (a fast move).  Corrupted reports within reach are single values between
  agreeing ones: a still arm showed neither in 10 s on ``sim://?corrupt=0.3`` (20 seeds), and every
  move from 3 mm/min and 0.02°/s up showed one within 6 reports of a kind.  It only says the arm
  moves (``jobflow.read_arm``); when it rests is the rule above.
"""

from __future__ import annotations

from collections import deque
from typing import Iterable

AGREEING_REPORTS = 2  # consecutive reports of a kind that must agree before their value counts
REST_CHECK_S = 0.6  # the arm counts as at rest when every kind reported the same readings this long
DISTINCT_REPORTS = 5  # ``MotionSeen``: consecutive reports of a kind, each another value, that show motion


def agreed(reports: Iterable) -> object | None:
    """The value the last ``AGREEING_REPORTS`` reports agree on; None while they disagree or
    fewer were read (for the pause reports: the pause state, one flipped byte never decides)."""
    reports = tuple(reports)[-AGREEING_REPORTS:]
    if len(reports) == AGREEING_REPORTS and reports.count(reports[0]) == AGREEING_REPORTS:
        return reports[0]
    return None


def agreeing_runs(readings: Iterable[tuple[float, object]]) -> list[tuple[float, float, object]]:
    """(first read, confirmed, value) of every run of ``AGREEING_REPORTS`` or more consecutive
    equal ``(time, value)`` readings, in order: when the run began, and when its
    ``AGREEING_REPORTS``-th report confirmed it (what a test of timing judges by: one corrupted
    report can make a run begin early, never confirm it)."""
    runs, value, count, start_s = [], None, 0, None
    for t, current in readings:
        if count and current == value:
            count += 1
        else:
            value, count, start_s = current, 1, t
        if count == AGREEING_REPORTS:
            runs.append((start_s, t, value))
    return runs


def reach(speed_per_s: float, elapsed_s: float, slack: float) -> float:
    """How far a reading may move in ``elapsed_s`` at ``speed_per_s`` (the arm's top speed), plus
    ``slack`` (the resolution and the jitter of when a report is read); never less than it."""
    return speed_per_s * (0.0 if 0.0 > elapsed_s else elapsed_s) + slack  # max(elapsed_s, 0.0)


def beyond_reach(before: tuple, after: tuple, reach: float) -> bool:
    """Two readings of three values differ by more than ``reach`` in any of them (the armstate's
    test of a jump; a NaN never counts as beyond)."""
    p, q, r = before
    x, y, z = after
    return abs(p - x) > reach or abs(q - y) > reach or abs(r - z) > reach


def known_still_s(changed_s: float, read_s: Iterable[float]) -> float:
    """How long readings are known unchanged: from their last change seen (``changed_s``) to the
    oldest of each kind's latest report (``read_s``) — not to now: a kind whose reports were lost
    or corrupted since says nothing about that time."""
    return min(read_s) - changed_s


def still_long_enough(changed_s: float, read_s: Iterable[float]) -> bool:
    """At rest: the readings known unchanged (``known_still_s``) for ``REST_CHECK_S``."""
    return known_still_s(changed_s, read_s) >= REST_CHECK_S


class MotionSeen:
    """Whether the reports show the arm moving (``Motion seen``), kind by kind in the order of
    ``kinds``; a new report of a kind is one whose read time changed."""

    def __init__(self, kinds: Iterable) -> None:
        self.latest: dict = {kind: deque(maxlen=DISTINCT_REPORTS) for kind in kinds}
        self.agreed: dict = {}  # kind -> the last value AGREEING_REPORTS consecutive reports agreed on
        self.read_s: dict = {}
        self.seen = False

    def read(self, readings: Iterable, read_s: Iterable[float]) -> bool:
        """Each kind's latest reading and when its report was read; True once motion is seen."""
        for (kind, latest), value, at_s in zip(self.latest.items(), readings, read_s):
            if self.read_s.get(kind) == at_s:  # no new report of this kind
                continue
            self.read_s[kind] = at_s
            latest.append(value)
            if agreed(tuple(latest)[-AGREEING_REPORTS:]) is not None:
                self.seen |= kind in self.agreed and self.agreed[kind] != value  # agreed on another value
                self.agreed[kind] = value
            elif len(latest) == DISTINCT_REPORTS and len(set(latest)) == DISTINCT_REPORTS:
                self.seen |= self.agreed.get(kind, latest) not in latest  # each report another value than agreed
        return self.seen
