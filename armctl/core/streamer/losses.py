"""Signs of loss: evidence that the arm skipped frames (dropped by a full FIFO, or cleared), or
ran slower than the time bound assumed when it confirmed frames.

Strategy: each sign is a sentence with its evidence (``losses``) and the earliest frame that
may not have run (``first_suspect_index``); a sign never moves the lower bound or the estimate.
Every check reads only agreed sightings (two reports of one stream), so one corrupted status
frame never raises one, and lost status frames only lengthen the intervals judged, so they
never raise one either:

* a gap (``check_gap``): the arm got from its last agreed sighting to a later frame sooner
  than the frames in between could take even ``speed_tolerance`` times faster than the model —
  the least motion between counts only frames whose length the plan knows, and the earlier
  sighting counts at the latest frame its report may lie on;
* a reversal (``check_reversal``): two reports in a row inside the path of a frame already
  known finished and on no pending path — the arm went back over its job;
* slowness (``check_slowness`` / ``check_time_bound``): pairs of agreed sightings along one
  frame prove the arm slower than the tolerance, on no later frame through the same point;
  told at the end of a job only when time confirmed frames at a narrower factor;
* a move not begun (``check_not_begun``): two position reports sampled after the time bound's
  deadline of the head frame still put the arm at its start, on no later frame (time holds off
  that frame from the first such report until they have said so, or two reports in a row agree
  on the arm elsewhere: the arm refused a target it cannot reach, or lost it);
* moving past the time bound (``moved_past_time_bound``): at the end, the arm seen moving after
  every frame written should have finished even on the slowest arm allowed for, with frames
  confirmed by time — the slowness a 10 ms move never shows in two sightings.
"""

from __future__ import annotations

from ..motion import Segment
from ..protocol import STATUS_PERIOD_S
from .constants import LOSS_SLACK_S
from .frames import where
from .geometry import TimeMemo, start_unknown
from .ledger import Ledger


class Losses:
    """The signs of loss found so far (see the module docstring)."""

    def __init__(self, ledger: Ledger, memo: TimeMemo, slowest_factor: float, kinematics_verified: bool) -> None:
        self.ledger, self.memo = ledger, memo
        self.kinematics_verified = kinematics_verified
        self.tolerance = slowest_factor  # the profile's speed_tolerance: what slowness is judged against
        self.fastest_factor = 1 / slowest_factor  # the arm at most this much faster than the model
        # Each sign of loss, a sentence with its evidence; ``first_suspect_index`` is the earliest
        # frame that may not have run (None: no sign).
        self.losses: list[str] = []
        self.first_suspect_index: int | None = None
        self.reversed_on: int | None = None  # the finished frame the last position report lay on (reversal check)
        self.sighting: dict[str, tuple] = {}  # stream → (index, at_s, could_be_on) of its last agreed sighting
        self.span_from: dict[str, tuple[int, float, float]] = {}  # stream → (index, least model s, at): first pair on a frame
        self.span_last: dict[str, tuple[int, float, float, float]] = {}  # stream → (index, model s lo, hi, at): last sighting
        self.too_slow: tuple[float, object] | None = None  # the arm seen slower than the tolerance on a frame
        self.standing_on: tuple[int, int] | None = None  # (head frame, reports after its deadline): ``check_not_begun``
        self.not_begun: int | None = None  # the last frame ``check_not_begun`` told
        self.moved_past_bound = False  # ``moved_past_time_bound`` told: the arm slower than the time bound allows
        self.slowest_proven = 0.0  # the most ``too_slow`` was in this job (a stale speed_factor: armctl/host/calibration.py)

    def found(self, sentence: str, suspect: int) -> None:
        """A sign of loss the caller concluded (``sentence``, for the summary); frame ``suspect``
        may not have run."""
        self.losses.append(sentence)
        self.suspect(suspect)

    def suspect(self, index: int) -> None:
        """Frame ``index`` may not have run."""
        if self.first_suspect_index is None or index < self.first_suspect_index:
            self.first_suspect_index = index

    def paused(self) -> None:
        """A slowness span must not include a pause."""
        self.span_from.clear()
        self.span_last.clear()

    def sighted(self, stream: str, previous: int, earliest: int, now: float, could_be_on) -> None:
        """Two reports of ``stream`` in a row, at least at frames ``previous`` then ``earliest``:
        the arm is at least at the smaller.  A gap found is told once: the next is judged from here."""
        if self.check_gap(stream, min(previous, earliest), now, could_be_on) or previous == earliest:
            self.sighting[stream] = (earliest, now, could_be_on)

    def check_reversal(self, xyz, match) -> None:
        """A sign of loss: the arm reported, twice in a row, on the inside of the path of a frame
        already known finished (the lower bound never passes the truth) and on no pending path —
        it went back over its job, which an arm running its frames in order never does.  ``xyz``
        is None when the report lies on a pending path (or one that cannot be judged).  Only
        straight and arc moves with a start the arm reported count, away from their ends (where
        the next frame begins); two reports on the same finished frame, not one, so a corrupted
        frame never raises it."""
        previous, self.reversed_on = self.reversed_on, None
        verified = self.kinematics_verified
        if xyz is None or not self.ledger.pending:
            return
        first = self.ledger.pending[0].index
        for sent in self.ledger.recent_sent:
            if sent.index >= first:
                break
            segment = sent.segment
            if segment.kind not in ("line", "arc") or segment.length <= 4 * sent.xyz_tolerance_mm:
                continue
            if start_unknown(segment, verified):
                continue  # its path starts where only the profile's kinematics say
            found = match(sent)
            if found is None or found[0] <= 0.0 or found[1] >= 1.0:
                continue
            self.reversed_on = sent.index
            if previous != sent.index:
                return
            self.losses.append(f"the arm was seen back on {where(sent)}, a frame already finished, twice in a row "
                               "and on no frame still to run: it did not run the job in order")
            self.suspect(first)
            return

    def check_not_begun(self, index: int | None, head, now: float, running_s: float | None,
                        left: bool = True) -> int | None:
        """A sign of loss: two position reports, each sampled after the time bound's deadline of
        the head frame ``index`` while the arm was seen running (``running_s``: when it last was,
        None while it reports a pause — a pause moves the deadline only once it ends), put the arm
        at its start and on no later frame (``evidence.standing_at_start``; None: this report
        does not), and no two reports in a row between them agreed on the arm elsewhere
        (``left``: this one and the one before did; a corrupted report is alone, and a lost one
        says nothing) — it did not begin a move that even an arm ``tolerance`` times slower than
        the model has finished by then: the arm refused it (a target out of its reach), lost it,
        or runs slower than the time bound allows.  From the first report at its start until two
        such reports have said so, or the arm was seen elsewhere, time must not count the frame
        done (the frame's index, for ``TimeBound.standing_at``); once told, it may (None)."""
        held = self.standing_on
        if index is None:
            if left or held is None or head is None or held[0] != head.index or held[0] == self.not_begun:
                self.standing_on = None
                return None
            return held[0]  # a report that says nothing of where the arm is keeps the hold
        if index == self.not_begun:
            self.standing_on = None
            return None
        # sampled after the deadline, which the arm reached running
        after = running_s is not None and min(now, running_s) - STATUS_PERIOD_S >= head.certain_end_s
        before = held[1] if held is not None and held[0] == index else 0
        self.standing_on = (index, before + after)
        if before + after < 2:
            return index
        self.not_begun = index
        self.losses.append(
            f"the arm stood at the start of {where(head)} past the time even an arm {self.tolerance:g}x slower "
            "than the model would have finished it: it did not run it (a target out of its reach, refused? "
            "dropped by a full FIFO?)")
        self.suspect(index)
        return None

    def check_gap(self, stream: str, index: int, now: float, could_be_on) -> bool:
        """A sign of loss: the arm, seen by this stream at ``now`` at least at frame ``index``,
        got there from its last agreed sighting sooner than the frames in between could take at
        the fastest plausible pace (``fastest_factor``): they were skipped — dropped by a full
        FIFO or cleared.  Sound on a good arm: lost status frames only lengthen the interval, and
        the earlier sighting counts at the latest frame its report may lie on (a repeated path,
        a frame this stream cannot judge) that is no later than the latest frame this report
        (``could_be_on``) may lie on — the arm runs its frames in order — so a return to the
        same place is no gap."""
        last = self.sighting.get(stream)
        recent = self.ledger.recent_sent
        if last is None or not recent or index <= last[0] + 1:
            return False
        first = recent[0].index
        if last[0] < first or index - first >= len(recent):
            return False  # out of the frames kept: no judgement
        since = last[1]
        at_k = recent[index - first]
        seen = recent[last[0] - first]
        gap_s = at_k.sure_before_s - seen.sure_before_s - seen.sure_s  # the least motion between
        allowed_s = now - since + LOSS_SLACK_S
        if gap_s * self.fastest_factor <= allowed_s:
            return False
        # Confirm: the latest frame the earlier report may lie on (the cost is paid only here).
        latest = next((sent.index for sent in reversed(recent) if could_be_on(sent)), index)
        upper = next((sent for sent in reversed(recent)
                      if last[0] <= sent.index <= latest and last[2](sent)), None)
        if upper is None or upper.index + 1 >= index:
            return False
        gap_s = at_k.sure_before_s - upper.sure_before_s - upper.sure_s
        if gap_s * self.fastest_factor <= allowed_s:
            return False
        skipped = index - upper.index - 1
        self.losses.append(
            f"the arm got from {where(upper)} to {where(at_k)} in {now - since:.2f} s, but the "
            f"{skipped} frame{'s' if skipped != 1 else ''} between take {gap_s:.2f} s of motion "
            f"(at least {gap_s * self.fastest_factor:.2f} s on an arm {1 / self.fastest_factor:g}x faster than the "
            "model): they were skipped (dropped by a full FIFO, or cleared)")
        suspect = last[0]  # the arm may have been on a later frame through the same point: not claimed
        self.suspect(suspect)
        return True

    def check_slowness(self, stream: str, index: int, segment: Segment, lo: float, hi: float, now: float,
                        could_be_on) -> None:
        """The time bound's hypothesis checked along one frame, on pairs of agreed sightings of
        this stream on it, so that one corrupted report (one that still lies on the path) cannot
        raise it: with sightings a then b, the arm was at least at min(a, b) at b's time and at
        most at max(a, b) at a's (it runs a frame forwards).  The first pair on the frame gives
        the first bound, each later pair the second; the arm then covered at most the model time
        between them, in at least the time between those readings less a status period at each
        end (a frame is sampled up to a period before it is read).  More than ``slowest_factor``
        times the model even so — and this report may lie on no later frame (``could_be_on``: a
        repeated path would let the arm be a lap further on; the cost is paid only here) — the
        arm is slower than the time bound allows (kept for ``check_time_bound``).  Pauses clear
        the sightings, as they do the pace's."""
        t_lo, t_hi = self.memo.time_at(segment, lo), self.memo.time_at(segment, hi)
        last = self.span_last.get(stream)
        self.span_last[stream] = (index, t_lo, t_hi, now)
        if last is None or last[0] != index:
            self.span_from.pop(stream, None)
            return
        first = self.span_from.get(stream)
        if first is None or first[0] != index:
            self.span_from[stream] = (index, min(last[1], t_lo), now)  # at least there, at b's time
            return
        model_span_s = max(last[2], t_hi) - first[1]  # at most there, at a's time
        arm_span_s = last[3] - first[2] - 2 * STATUS_PERIOD_S
        if model_span_s <= 0 or arm_span_s <= 0:
            return
        slowest = arm_span_s / model_span_s
        if slowest <= self.tolerance or (self.too_slow is not None and slowest <= self.too_slow[0]):
            return
        k = index - self.ledger.pending[0].index
        if any(could_be_on(self.ledger.pending[j]) for j in range(k + 1, len(self.ledger.pending))):
            return  # the arm may be on a later frame through the same point: no judgement
        self.too_slow = (slowest, self.ledger.pending[k])
        self.slowest_proven = max(self.slowest_proven, slowest)

    def check_time_bound(self, least: float | None, time_proves: bool) -> None:
        """A sign of loss, told at the end of a job: the arm was proven to run a frame slower than
        the profile's ``speed_tolerance`` (``check_slowness``) and slower than the factor the
        time bound used when it first confirmed a frame (before a measured pace widened it), so
        what time confirmed may not have run when more frames were written (dropped by a full
        FIFO).  Said only when time confirmed a frame and was still trusted (not ``cleared``)."""
        if self.too_slow is None or least is None or self.too_slow[0] <= least or not time_proves:
            return
        slowest, sent = self.too_slow
        self.too_slow = None
        self.losses.append(
            f"the arm ran {where(sent)} at least {slowest:.2f}x slower than the model, but the time bound allowed "
            f"{least:g}x (the profile's [connector] speed_tolerance) when it confirmed frames: they may not have run "
            "when more were written (dropped by a full FIFO?); run `armctl probe` again")
        suspect = self.ledger.first_time_only_index or 0
        self.suspect(suspect)

    def moved_past_time_bound(self, moved_after_s: float | None, bound_s: float) -> None:
        """A sign of loss, told at the end of a job: the arm still moved after ``bound_s`` (when
        even an arm ``speed_tolerance`` times slower than the model would have finished every frame
        written), and time confirmed frames — so the arm is slower than the time bound allowed,
        and what time confirmed may not have run when more frames were written (a full FIFO drops
        them silently).  The move counts from the last reading at the value before it, agreed by
        two reports in a row as the new one is (``moved_after_s``: the job engine's
        ``Readings.work_s``; corrupted reports never agree), less a status period (that frame
        may have been built so long before it was read); an SD program's bound never runs out,
        so it never raises this."""
        if moved_after_s is None or not self.ledger.confirmed_by_time or moved_after_s - STATUS_PERIOD_S <= bound_s:
            return
        self.moved_past_bound = True
        self.found(f"the arm still moved after {moved_after_s - STATUS_PERIOD_S:.2f} s, when an arm {self.tolerance:g}x "
                   f"slower than the model would have finished every frame written ({bound_s:.2f} s): it is slower than "
                   "the profile's [connector] speed_tolerance allows, so frames counted done by time may not have run "
                   "when more were written (dropped by a full FIFO?); run `armctl probe`",
                   self.ledger.first_time_only_index or 0)
