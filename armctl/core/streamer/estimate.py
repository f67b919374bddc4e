"""The estimate: when the arm ends each pending frame, and how much slower than the model it runs.

Strategy: the model's times, re-anchored on every sighting and never trusted for proof.  Each
frame's ``est_end_s`` starts as the model has it (no sooner than it landed, after the frame
before).  A sighting's candidates each say the arm is now within a window of that frame's
time — a short one on a path that moves, the whole frame on one that does not move what was
observed; the window nearest the estimate wins and the estimate moves by the least that puts
``now`` in it (``reanchor``), every later frame following.  So a still frame never pushes the
estimate while the estimate agrees with it, and an arm standing still holds it back.

The ``pace`` (the arm's seconds ÷ the model's) is measured from two agreeing sightings on one
segment at least ``PACE_MIN_SPAN_S`` of model time apart, the largest of the last few, never
below 1 and at most ``PACE_MAX``.  From ``PACE_FOLLOWED`` on, the frames are followed at that
pace from where a sighting inside a moving path last pinned the arm (``arm_ends``).  The
estimate and the pace shape only the lead (``Gate``) and ``queued_seconds``; the lower bound
never reads them.  ``plan_changes`` counts every change a caller waiting on the estimate needs
to hear of.
"""

from __future__ import annotations

import math
from bisect import bisect_left
from collections import deque

from .constants import PACE_FOLLOWED, PACE_MAX, PACE_MIN_SPAN_S, PACE_SAMPLES, SCAN_WINDOW_FRAMES
from .frames import SentFrame, est_end
from .geometry import TimeMemo, estimate_off_s, time_window
from .ledger import Ledger


# Rounding in a frame's start and in ``Segment.time_at_fraction`` (ulps of seconds) is far below
# this: a bound on how far off the estimate is, less this much, is never above the true one.
_OFF_MARGIN_S = 1e-6


class Estimate:
    """The pending frames' estimated ends and the arm's measured pace (see the module docstring)."""

    def __init__(self, ledger: Ledger, memo: TimeMemo) -> None:
        self.ledger, self.memo = ledger, memo
        # Where a sighting last pinned the arm on the estimate: (time, frame, model s of it left);
        # ``arm_ends`` follows the frames at the measured pace from there
        self.pin: tuple[float, int, float] | None = None
        self.pace = 1.0  # the arm's seconds ÷ the model's, measured (see the module docstring)
        # Bumped whenever an observation changes what ``next_write_time`` reads besides the
        # lower bound (the estimate's end times, the pace): a status frame that moved neither
        # cannot change when the next frame may go (``Job.receive_status``'s news).
        self.plan_changes = 0
        self.pace_samples: deque[float] = deque(maxlen=PACE_SAMPLES)
        self.pace_from: dict[str, tuple[int, float, float]] = {}  # stream → (index, model s, now)
        # Pending frames (indexes) whose estimated end is sooner than the frame's before them: a
        # re-anchoring moved them (``_note_order``); every other pending frame ends in order.
        self.out_of_order: set[int] = set()

    def written(self, frame: SentFrame, previous: SentFrame | None) -> None:
        """Give a frame just written its estimated end: no sooner than its last byte left the
        wire, after the frame before it."""
        wire_end = frame.wire_end_s
        est_start = max(wire_end, previous.est_end_s if previous else wire_end)
        if previous is None:
            self.pin = (est_start, frame.index, frame.segment.duration_s)  # the arm waits for it: it starts on the arm's time
        frame.est_end_s = est_start + frame.segment.duration_s

    def paused(self) -> None:
        """The arm held still: where it was pinned no longer says where it is, and a pace
        sample must not span a pause (arrival mode freezes a move)."""
        self.pin = None
        self.pace_from.clear()

    def estimated_finish_s(self) -> float | None:
        pending = self.ledger.pending
        return pending[-1].est_end_s if pending else None

    def queued_seconds(self, now: float) -> float:
        """Estimated motion queued ahead of the arm: when it will finish everything, from now —
        on an arm measured slower than the model, the later of the estimate and the frames
        followed at its pace (``arm_ends``: the estimate may have run ahead of the arm)."""
        pending = self.ledger.pending
        if not pending:
            return 0.0
        ends = self.arm_ends()
        tail_s = pending[-1].est_end_s if ends is None else max(ends[-1], pending[-1].est_end_s)
        return max(0.0, tail_s - now)

    def waiting_seconds(self, now: float) -> float:
        """Estimated motion in frames the arm has not begun yet: ``queued_seconds`` without the
        rest of the frame in progress.  This is what the lead bounds."""
        pending = self.ledger.pending
        if not pending:
            return 0.0
        tail_s = pending[-1].est_end_s
        current_end_s = next((sent.est_end_s for sent in pending if sent.est_end_s > now), tail_s)
        return max(0.0, tail_s - max(now, current_end_s))

    def arm_ends(self) -> list[float] | None:
        """When the arm ends each pending frame in its own seconds, on an arm measured slower than
        the model (None otherwise: the estimate's ends are the arm's).  The estimate runs at the
        model's pace from its last re-anchoring, so on a slow arm it has begun frames the arm has
        not (a delay, an M code, a PWM change: frames no sighting re-times), and the lead would
        hold more of the arm's seconds than it says (issue 21: 3.6 s of motion after a Ctrl-C
        against a 2.15 s promise, an arm 1.3x slower at 115200).  So from where the last pinning
        sighting had the arm (``_pin``: at that time, that much of that frame's model time left)
        the frames follow at the measured ``pace``, each no sooner than it landed (a pause
        reported drops the pin: the estimate again until the next).  Not the later of this and
        the estimate's own end: an estimate re-anchored late on a still frame would then hold
        the line idle (an arm 2x slower, unprobed: 1.32x its physical bound; 1.04x without).
        Frames before the pinned one end where the estimate has them."""
        pin, pace = self.pin, self.pace
        if pin is None or pace < PACE_FOLLOWED:
            return None
        at_s, index, left_s = pin
        end_s = at_s + left_s * pace  # the pinned frame's end
        ends = []
        for sent in self.ledger.pending:
            if sent.index < index:
                ends.append(sent.est_end_s)
                continue
            if sent.index > index:
                end_s = max(sent.wire_end_s, end_s) + sent.segment.duration_s * pace
            ends.append(end_s)
        return ends

    def pin_estimate(self, candidates: list[tuple[int, float, float]], now: float) -> None:
        """``pin`` where this sighting pins the estimate: the estimate has the arm in the window of
        a candidate inside a path that moves (a short window).  One on a still frame (a delay, a
        PWM change) or at a path's end only bounds it: the arm may rest there in frames the
        estimate ran through already, an arm slower than the model still in the first."""
        pending = self.ledger.pending
        if not pending:
            return
        first = pending[0].index
        for index, lo, hi in candidates:
            k = index - first
            if 0 <= k < len(pending) and estimate_off_s(pending[k], lo, hi, now, self.memo.time_at) == 0.0:
                sent = pending[k]
                if sent.segment.length > 0 and lo > 0.0 and hi < 1.0:
                    self.pin = (now, sent.index, max(0.0, sent.est_end_s - now))
                return

    def reanchor_beyond(self, match, end: int, now: float) -> None:
        """The estimate (never the lower bound) re-anchored on a report that lies on the path of
        a pending frame at or after ``end``, past a frame the stream cannot judge (a move from a
        joint end the profile's kinematics do not verify, whose real length and path only the
        arm knows).  Without it the estimate runs on by the plan while the arm is still on that
        frame, so the lead counts less motion queued than there is and an abort outruns the stop
        bound (``armctl bench``'s ``kinematics`` row: 3.50 s moved against 2.88 s).  A report
        on one of those paths is evidence for the estimate only: it may also lie on the frame
        that cannot be judged, so nothing is proven by it.  Flat cost: the frames searched are
        a window around the frame the estimate has in progress."""
        pending = self.ledger.pending
        current = next((k for k in range(end, len(pending)) if pending[k].est_end_s > now), len(pending) - 1)
        lo_k, hi_k = max(end, current - SCAN_WINDOW_FRAMES), min(len(pending), current + SCAN_WINDOW_FRAMES)
        candidates = []
        for k in range(lo_k, hi_k):
            found = match(pending[k])
            if found is not None:
                candidates.append((pending[k].index, *found))
        if candidates:
            self.reanchor(candidates, now)

    def reanchor(self, candidates: list[tuple[int, float, float]], now: float) -> None:
        """Re-time the pending frames from the candidate the estimate finds most plausible.

        Each candidate says: the arm is now between fractions ``lo`` and ``hi`` of that frame's
        path, i.e. between two moments of its segment — a short window on a segment that moves,
        the whole segment for one that does not move what was observed (a delay, an M code, a
        PWM-only or attitude-only frame seen by position).  The candidate whose window the
        estimate is nearest to wins, and the estimate is moved by the least that puts ``now``
        inside that window (not at all if it already is); every later frame follows.  So a
        still frame never pushes the estimate while the estimate agrees with it, and an arm
        standing still (paused, or slower than the model) holds the estimate back.
        """
        pending = self.ledger.pending
        if not pending:
            return
        best = self._nearest(candidates, now)
        if best is None or best[0] == 0.0:
            return
        _, k, lo, hi = best
        self.plan_changes += 1
        sent = self.ledger.pending[k]
        t_lo, t_hi = time_window(sent.segment, lo, hi, self.memo.time_at)
        start = sent.est_end_s - sent.segment.duration_s
        start = now - t_lo if now < start + t_lo else now - t_hi
        sent.est_end_s = start + sent.segment.duration_s
        if sent.group_index != sent.index and k > 0:
            self.ledger.pending[k - 1].est_end_s = start  # its G300: the arc's start
        previous_end_s = sent.est_end_s
        pending = self.ledger.pending
        last = k
        for j in range(k + 1, len(pending)):
            nxt = pending[j]
            end_s = max(nxt.wire_end_s, previous_end_s) + nxt.segment.duration_s
            if end_s == nxt.est_end_s:
                break  # and so are the frames after it
            nxt.est_end_s = previous_end_s = end_s
            last = j
        self._note_order(k - 1 if sent.group_index != sent.index and k > 0 else k, last)

    def _note_order(self, k: int, last: int) -> None:
        """The ends of pending frames ``k``…``last`` moved: each of them now ends no sooner than the
        one before it, and so does the frame after them (where the chain stopped, nothing moved);
        only frame ``k`` may end sooner than the frame before it (``out_of_order``)."""
        pending, out_of_order = self.ledger.pending, self.out_of_order
        if out_of_order:
            for j in range(k + 1, min(last + 2, len(pending))):
                out_of_order.discard(pending[j].index)
        if k > 0:
            if pending[k - 1].est_end_s > pending[k].est_end_s:
                out_of_order.add(pending[k].index)
            else:
                out_of_order.discard(pending[k].index)

    def began_before(self, threshold_s: float) -> float | None:
        """The estimated end of the pending frame before the first that ends at or after
        ``threshold_s`` (that one's start: None when it is the first).  The ends are in order
        but where ``out_of_order`` says (a frame re-anchored sooner than the one before it
        ended): in order, a bisection finds it; else one pass from the oldest."""
        pending, out_of_order = self.ledger.pending, self.out_of_order
        if out_of_order:
            first = pending[0].index
            for index in [index for index in out_of_order if index <= first]:
                out_of_order.discard(index)  # its pair left the queue
        if not out_of_order:
            i = bisect_left(pending, threshold_s, key=est_end)
            return pending[i - 1].est_end_s if i else None
        began_s = None
        for sent in pending:
            end_s = sent.est_end_s
            if end_s >= threshold_s:
                break
            began_s = end_s
        return began_s

    def _nearest(self, candidates, now: float):
        """(off, k, lo, hi) of the first candidate whose window the estimate is nearest to
        (``estimate_off_s``; the first at 0 ends the search), k its place in the queue; None with
        no pending candidate.  Flat cost: a frame that ended ``now − est_end`` ago (or begins
        ``start − now`` from now) is at least that far off, so once one candidate is reckoned,
        a candidate bound to be farther (by more than ``_OFF_MARGIN_S``) is never reckoned."""
        pending, time_at = self.ledger.pending, self.memo.time_at
        first = pending[0].index
        bounds = []
        for index, lo, hi in candidates:
            if index < first:
                bounds.append(None)
                continue
            sent = pending[index - first]
            end_s = sent.est_end_s
            least_s = end_s - sent.segment.duration_s - now  # (starts that long from now)
            if hi != math.inf and now - end_s > least_s:
                least_s = now - end_s  # (ended that long ago)
            bounds.append(least_s - _OFF_MARGIN_S)
        reckoned = [b for b in bounds if b is not None]
        if not reckoned:
            return None
        # one candidate reckoned first, the one most likely nearest: its ``off`` bounds the rest
        k_star = bounds.index(min(reckoned))
        index, lo, hi = candidates[k_star]
        off_star = estimate_off_s(pending[index - first], lo, hi, now, time_at)
        best = None
        for j, (index, lo, hi) in enumerate(candidates):
            least_s = bounds[j]
            if least_s is None or least_s > off_star:
                continue  # not pending, or farther than a candidate already reckoned: never the nearest
            off = off_star if j == k_star else estimate_off_s(pending[index - first], lo, hi, now, time_at)
            if best is None or off < best[0]:
                best = (off, index - first, lo, hi)
            if off == 0.0:
                break
        return best

    def pace_window(self, stream: str, index: int, candidates) -> tuple[SentFrame, float, float] | None:
        """Where this stream's agreed sighting on frame ``index`` puts the arm inside a moving
        path (frame, lo, hi), for a pace sample and the slowness check; None when it cannot
        time the arm (the frame's time may be any, the window touches an end of the path, or
        the path does not move: then the stream's last pace sighting is dropped)."""
        pending = self.ledger.pending
        if not pending or index < pending[0].index:
            return None
        found = None
        for k, lo, hi in candidates:
            if k == index:
                found = (lo, hi)
                break
        sent = pending[index - pending[0].index]
        if not sent.timing_known:
            return None  # its time may be any: no pace, no slowness from it
        segment = sent.segment
        if found is None or segment.length <= 0 and segment.kind != "joint":
            self.pace_from.pop(stream, None)
            return None
        lo, hi = found
        if lo <= 0.0 or hi >= 1.0:
            return None  # a window cut at an end of the path: its middle is not where the arm was
        return sent, lo, hi

    def sample_pace(self, stream: str, sent: SentFrame, lo: float, hi: float, now: float) -> bool:
        """One more pace sample when this stream saw the arm on the same frame before, at least
        ``PACE_MIN_SPAN_S`` of model time earlier along its path (two sightings on one segment:
        the arm ran between them, neither waiting for the line nor between frames).  True when
        a sample was taken."""
        index = sent.index
        model_s = sent.segment.time_at_fraction((lo + hi) / 2)
        last = self.pace_from.get(stream)
        if last is None or last[0] != index or model_s < last[1]:
            self.pace_from[stream] = (index, model_s, now)
            return False
        if model_s - last[1] < PACE_MIN_SPAN_S:
            return False
        self.pace_samples.append((now - last[2]) / (model_s - last[1]))
        self.pace_from[stream] = (index, model_s, now)
        pace, self.pace = self.pace, min(PACE_MAX, max(1.0, *self.pace_samples))
        if self.pace != pace:
            self.plan_changes += 1
        return True
