"""The connector's capacity, exactly, with frames that do not move the arm.

Strategy: a long delay (G4) keeps the arm busy while PWM-only frames (a joint move to the
joints the arm reports, a new PWM) are written behind it at the line rate, more than the
connector can hold.  Nothing leaves the FIFO while the delay runs, so it accepts exactly
``fifo_frames`` of them — the frames it holds behind the one the arm executes (whether the
executing delay keeps a slot of its own is not observable; this number is) — and drops the
rest.  When the delay ends the arm runs the accepted frames in order; the PWM it finally reports
(status kind 4) names the last frame accepted.

A PWM change takes the servo time (``timing.pwm_change_s`` on the model; 0.3 s), so giving
all 300 frames distinct values would cost minutes.  Two rounds instead: round 1 changes the
value every ``BLOCK`` frames (the final value names a block of 16); round 2 repeats the value
the arm now holds (a frame that changes nothing takes no time) up to that block and gives each
frame in it its own value.  The end of a round is seen, not assumed: the reported PWM has not
changed for ``max(QUIET_S, 3 ×`` the longest step seen between new values``)``, nor for as long as
the frames that may follow the last new value unseen can take (``Pace``): a frame that repeats the
PWM takes no time on the document's arm, but an arm that takes 100 ms before every command
spends 1.5 s on a block's 15 repeats and 19 s on round 2's 192 (taken for the round's end, they
made the FIFO 2 frames, "sure", and the arm still ran them when the timed moves began).

The hold is proven, not assumed, at any line rate: the fillers go ``FILL_AHEAD_S`` ahead of the
wire (a host wakes every 20-30 ms; at 115200 a frame takes 4.2 ms), and a round counts only if
the last one landed — as the port's reports prove it (``Probe.landed_by``, landing.py) —
``HOLD_MARGIN_S`` before the delay could end (``Probe.earliest_landing`` + its length).  A round
not proven for want of time is tried again with a longer delay (``ATTEMPTS``); one whose PWM
changed before its last frame landed proves nothing.  Unproven: unsure, and the evidence says
what to set by hand.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from itertools import groupby

from ..core.protocol import PWM_RANGE_US, Delay, PauseStatus
from .plan import AGREEING_FRAMES, LIKELY, SURE, UNSURE, Finding, Send, Wait
from .steps import DOCUMENTED, QUIET_S, pwm_frame, settle

MAX_FRAMES = 300  # fillers written per round: the document's 200 and half again
BLOCK = 16
STEP_US = 5  # PWM step between values: the gripper barely moves (≤ 100 µs from where it was)
FILL_MARGIN_S = 1.0  # the delay outlasts the last filler's landing by this much (as planned)
# The fillers go up to this much line time ahead of the wire: the port's buffer keeps the line
# busy between the host's wake-ups (every 20-30 ms: at 115200 a frame takes 4.2 ms).  0.2 s is
# 2.3 KB at 115200, within any port's buffer (some KB), 4 frames at 9600.
FILL_AHEAD_S = 0.2
# The last filler must have landed this long before the delay can end: an arm whose delay timer
# runs short by up to this much (ticks of 30 ms, say) still held it.
HOLD_MARGIN_S = 0.1
ATTEMPTS = 3  # a round whose hold was not proven for want of time is tried again, the delay longer
# A round that shows nothing new for this long beyond its expected quiet is given up: after the
# delay's end, or after the last new value — an arm that takes 0.5 s before every command runs a
# round's 200 frames in over 100 s, still running, not stuck (``_until_settled``).
ROUND_LIMIT_S = 60.0


def _changes(probe, since_s: float) -> list[tuple[float, int]]:
    """(time, PWM) of each kind-4 frame since ``since_s`` whose PWM differs from the frame before.
    Single frames, not agreed runs: while the FIFO drains a value may last less than two frames
    of its kind (a corrupted frame adds a change: ``_Round.steps`` leaves its blips out)."""
    changes, previous = [], None
    for t, frame in probe.seen.since(PauseStatus.KIND, since_s):
        if previous is not None and frame.pwm_us != previous:
            changes.append((t, frame.pwm_us))
        previous = frame.pwm_us
    return changes


def _direction(start_us: int, span_us: int) -> int:
    return 1 if start_us + span_us <= PWM_RANGE_US[1] else -1


@dataclass(frozen=True)
class Pace:
    """How long one filler takes the arm, as round 1's new values show (one every ``BLOCK``
    frames): ``change_s``, a frame that changes the PWM (the first new value after the delay's
    end), and ``repeat_s``, at most, one that repeats it (a block's step ÷ its ``BLOCK − 1``
    repeats; with one step seen, a change's time: no frame takes longer than that)."""

    change_s: float
    repeat_s: float

    @classmethod
    def of(cls, gaps: list[float]) -> Pace:
        """From round 1's steps between new values, the first from the delay's end."""
        return cls(gaps[0], max(gaps[1:]) / (BLOCK - 1) if len(gaps) > 1 else gaps[0])


@dataclass(frozen=True)
class Fill:
    """One round's outcome: the PWM the arm ended at (None: the round proves nothing), why, and
    how sure the hold was; ``late_s``: how much longer the delay would have had to hold (a retry
    with a delay that much longer may prove it)."""

    final: int | None
    evidence: str
    confidence: str = SURE
    late_s: float | None = None
    hold: dict = field(default_factory=dict)
    pace: Pace | None = None  # round 1's (``Pace.of``), for round 2


@dataclass
class _Round:
    """One round's frames as written: the delay (its length, when it was handed to the port, the
    stream position after it, when the line model expects it to land) and the fillers (the
    stream position after the last, when the model expects that one to land)."""

    values: list[int]
    start_us: int
    delay_s: float
    delay_written_s: float
    delay_landed_s: float = 0.0
    delay_end: int = 0
    last_landed_s: float = 0.0
    last_end: int = 0

    @property
    def end_s(self) -> float:
        """When the delay ends, as the line model expects."""
        return self.delay_landed_s + self.delay_s

    def earliest_end_s(self, probe) -> float:
        """The delay cannot end sooner: its landing (not before write() + its wire time, nor
        while the port still held it) + its length."""
        return probe.earliest_landing(self.delay_end, self.delay_written_s) + self.delay_s

    def delay_ended_s(self, probe) -> float:
        """When the delay ended, as far as the reports can tell: the model's end, or later as the
        port's reports prove it began (a buffer may have held it)."""
        return max(self.end_s, self.earliest_end_s(probe))

    def landed_by_s(self, probe) -> float | None:
        """The last filler has landed by then (None: the port still holds it)."""
        return probe.landed_by(self.last_end, self.last_landed_s)

    def queued_until_s(self, probe, silent_s: float, pace: Pace | None) -> float:
        """When the arm may have run the round's frames after the last new value seen, at the pace
        seen (``pace``, else this round's so far; a frame time each before any): the restore step
        waits for it after a Ctrl-C (1.5 s of quiet had passed for it, and the PWM put back queued
        behind a block's repeats, 8 s at 0.5 s a frame, or round 2's 192 leading ones, 100 s)."""
        start_s = self.delay_ended_s(probe)
        gaps, reached = self._progress(probe)
        pace = pace or (Pace.of(gaps) if gaps else Pace(probe.frame_s, probe.frame_s))
        rest = self.values[reached + 1:]
        changes = sum(1 for a, b in zip([self.values[reached] if reached >= 0 else self.start_us, *rest], rest) if a != b)
        return (max(start_s + silent_s, start_s + sum(gaps)) + changes * max(probe.frame_s, pace.change_s)
                + (len(rest) - changes) * max(probe.frame_s, pace.repeat_s))

    def steps(self, probe) -> list[float]:
        """The steps between the new values reported since the delay's end — the model's, or later
        as the port's reports prove it began (a buffer may have held it) — the first from that end.
        A new value counts only if it is further along the values sent than the last one counted
        and the next frame (while there is none: counted, the round not ended on it) stays there or
        goes further: a corrupted frame is a blip and back (its short steps, taken for round 1's
        pace, let the quiet of a block's repeats pass for the round's end: fifo_frames 2, "sure",
        for 200), and a PWM one byte off is often one sent."""
        return self._progress(probe)[0]

    def _progress(self, probe) -> tuple[list[float], int]:
        """``steps``, and the last place in the values sent that the last new value counted holds."""
        start_s = self.delay_ended_s(probe)
        last = {value: k for k, value in enumerate(self.values)}  # a value's last place in the sequence
        frames = [(t, frame.pwm_us) for t, frame in probe.seen.since(PauseStatus.KIND, start_s - 1.0)]
        times, reached = [], last.get(self.start_us, -1)
        for (_, before), (t, value), (_, after) in zip(frames, frames[1:], [*frames[2:], (None, None)]):
            stays = after is None or last.get(value, -1) <= last.get(after, -1)
            if t >= start_s and value != before and reached < last.get(value, -1) and stays:
                times.append(t)
                reached = last[value]
        return [b - a for a, b in zip([start_s, *times], times)], reached

    def settled(self, probe, silent_s: float, pace: Pace | None) -> bool:
        """The arm has run what it accepted: the port holds no filler, and the PWM has been quiet
        long enough since the delay's end (``silent_s`` with no new value: the quiet of a delay
        still running never passes for the end of the round) or since the last new value: three
        steps between new values, a changing frame's time thrice, and the repeats that may follow
        it at ``pace`` (round 1's; round 1 its own so far).  Round 2's first step covers its
        leading repeats (``silent_s`` allowed for them): not a step between new values."""
        if self.landed_by_s(probe) is None:
            return False
        gaps = self.steps(probe)
        if not gaps:
            return probe.now_s - self.delay_ended_s(probe) >= silent_s
        pace = pace or Pace.of(gaps)
        leading = next((k for k, v in enumerate(self.values) if v != self.start_us), 0)
        between = gaps[1:] if leading else gaps
        trailing = max(len(list(run)) - 1 for _, run in groupby(self.values[leading:]))  # repeats after a new value
        quiet_s = max(QUIET_S, 3 * max(between, default=0.0), 3 * pace.change_s, trailing * pace.repeat_s)
        return probe.now_s - (self.delay_ended_s(probe) + sum(gaps)) >= quiet_s


def fill_round(probe, values: list[int], start_us: int, extra_s: float = 0.0, pace: Pace | None = None):
    """Delay, then ``values`` as PWM-only frames, written up to ``FILL_AHEAD_S`` ahead of the
    wire; a ``Fill``.  The round counts only if the last frame landed while the delay held the
    arm: proven from the port's reports (``probe.wire``), else assumed from the line model.
    ``pace``: round 1's, for round 2 (None: round 1, which measures it)."""
    wire = probe.wire
    after_sent_s = wire.after_sent_bytes * wire.byte_s
    count = len(values)
    delay_s = math.ceil(((count + 1) * probe.frame_s + after_sent_s + FILL_MARGIN_S + extra_s) * 10) / 10
    fill = _Round(values, start_us, delay_s, probe.now_s)
    fill.delay_landed_s = yield Send(Delay(delay_s * 1000))
    fill.delay_end = wire.written_bytes
    probe.known.busy_until_s = fill.end_s
    fill.last_landed_s = fill.delay_landed_s
    for value in values:
        fill.last_landed_s = yield Send(pwm_frame(probe, value), ahead_s=FILL_AHEAD_S)
    fill.last_end = wire.written_bytes
    # Frames that repeat the PWM show nothing while they run: until a change is seen, allow them
    # a frame time each, or round 1's pace if slower, and the delay may end as much later than
    # its earliest end as an adapter may hold it.
    repeats = sum(1 for a, b in zip([start_us, *values], values) if a == b)
    silent_s = QUIET_S + after_sent_s + repeats * max(probe.frame_s, pace.repeat_s if pace else 0.0)
    probe.known.queued_until_s = lambda: fill.queued_until_s(probe, silent_s, pace)  # (for a Ctrl-C meanwhile)
    yield from _until_settled(probe, fill, silent_s, pace)
    probe.known.queued_until_s = None
    probe.known.busy_until_s = max(probe.known.busy_until_s, probe.now_s)
    judged = _judged(probe, fill, fill.settled(probe, silent_s, pace))
    gaps = fill.steps(probe)
    return dataclasses.replace(judged, pace=pace or (Pace.of(gaps) if gaps else None))


def _until_settled(probe, fill: _Round, silent_s: float, pace: Pace | None):
    """Wait until ``fill`` settles, or until it has shown nothing new for ``ROUND_LIMIT_S`` after
    the delay's end and the quiet its leading repeats may take (``silent_s``), or after its last
    new value; never longer than ``ROUND_LIMIT_S`` for each block of ``BLOCK`` frames (a noisy
    line's corrupted frames are news too: the wait stays bounded)."""
    last_s = fill.end_s + silent_s + ROUND_LIMIT_S * math.ceil(len(fill.values) / BLOCK)

    def news_s() -> float:
        start_s = fill.delay_ended_s(probe)
        return min(start_s + max(silent_s, sum(fill.steps(probe))), last_s)

    while True:
        deadline_s = news_s() + ROUND_LIMIT_S
        yield Wait(deadline_s, lambda: fill.settled(probe, silent_s, pace) or news_s() + ROUND_LIMIT_S > deadline_s)
        if fill.settled(probe, silent_s, pace) or news_s() + ROUND_LIMIT_S <= deadline_s:
            return


def _judged(probe, fill: _Round, settled: bool) -> Fill:
    """What a round proves: the final PWM if the last filler landed ``HOLD_MARGIN_S`` before the
    delay could end and the PWM did not change before then; else why not."""
    wire, written_s, delay_s = probe.wire, fill.delay_written_s, fill.delay_s
    ends_s, landed_by_s = fill.earliest_end_s(probe), fill.landed_by_s(probe)
    confidence, how = (SURE, "the port's reports prove") if wire.reporting else \
        (LIKELY, "the line model expects (the port does not say what it sent)")
    hold = {"delay_s": delay_s, "delay_ends_earliest_s": round(ends_s - written_s, 3)}
    if landed_by_s is None:
        return Fill(None, f"the port still held {wire.unsent_bytes()} bytes {probe.now_s - written_s:.1f} s after "
                          f"the {delay_s:g} s delay was written: when the frames landed is not known", UNSURE, None, hold)
    hold["last_landed_by_s"] = round(landed_by_s - written_s, 3)
    late_s = landed_by_s + HOLD_MARGIN_S - ends_s
    if late_s > 0:
        return Fill(None, f"the last of the {len(fill.values)} frames landed by {landed_by_s - written_s:.2f} s ({how}), but "
                          f"the {delay_s:g} s delay may have ended at {ends_s - written_s:.2f} s (both from when the delay "
                          f"was written; {HOLD_MARGIN_S:g} s to spare needed): the delay did not surely hold the arm",
                    UNSURE, late_s, hold)
    sent = set(fill.values)
    early = [(t, v) for t, v in _changes(probe, fill.delay_landed_s)
             if t < landed_by_s and v in sent and v != fill.start_us]
    if len(early) >= AGREEING_FRAMES:
        return Fill(None, f"the PWM changed {early[0][0] - written_s:.2f} s after the {delay_s:g} s delay was written, "
                          f"before the last frame landed ({landed_by_s - written_s:.2f} s): the arm did not hold "
                          "for the delay", UNSURE, None, hold)
    final = probe.seen.agreed(PauseStatus.KIND, fill.end_s, lambda f: f.pwm_us)
    if not settled or final is None:
        return Fill(None, f"the PWM had not settled: nothing new for {ROUND_LIMIT_S:g} s", UNSURE, None, hold)
    return Fill(final[1], f"{len(fill.values)} PWM-only frames behind a {delay_s:g} s delay, the last landed by "
                          f"{landed_by_s - written_s:.2f} s and the delay ending at {ends_s - written_s:.2f} s at "
                          f"the earliest ({how}); the arm ended at PWM {final[1]} µs", confidence, None, hold)


def held_round(probe, make_values, pace: Pace | None = None):
    """``fill_round`` on ``make_values(the PWM the arm holds)``, again with a longer delay while
    the hold was not proven for want of time (up to ``ATTEMPTS``): (the Fill, the values sent,
    the PWM they started from, what earlier attempts showed)."""
    extra_s, tried = 0.0, []
    while True:
        start_us = _current_pwm(probe)
        values = make_values(start_us)
        fill = yield from fill_round(probe, values, start_us, extra_s, pace)
        if fill.final is not None or fill.late_s is None or len(tried) + 1 == ATTEMPTS:
            return fill, values, start_us, tried
        tried.append(fill.evidence)
        extra_s += fill.late_s + FILL_MARGIN_S


def _accepted(values: list[int], final: int, start_us: int) -> int | None:
    """How many of ``values`` (in order) were accepted, if the arm ends at ``final``."""
    indexes = [k + 1 for k, v in enumerate(values) if v == final]
    if indexes:
        return max(indexes)
    return 0 if final == start_us else None


def _round1(start_us: int) -> list[int]:
    blocks = math.ceil(MAX_FRAMES / BLOCK)
    direction = _direction(start_us, STEP_US * (blocks + 1))
    return [start_us + direction * STEP_US * (k // BLOCK + 1) for k in range(MAX_FRAMES)]


def _round2(lead_count: int, tail: int):
    def values(start_us: int) -> list[int]:
        direction = _direction(start_us, STEP_US * (BLOCK + 1))
        return [start_us] * lead_count + [start_us + direction * STEP_US * (k + 1) for k in range(tail)]
    return values


def _by_hand(why: str) -> str:
    return (f"{why}. Count the frames your connector holds and set `[connector] fifo_frames = <that number>` in "
            f"armctl.toml by hand: until then armctl assumes the document's {DOCUMENTED['fifo_frames']}, and a smaller "
            "FIFO drops frames silently")


def _attempts(tried: list[str], last: str) -> str:
    """``last``, after what the attempts before it showed (each made the next one's delay longer)."""
    return "".join(f"attempt {k + 1}: {why}; tried again with a longer delay: " for k, why in enumerate(tried)) + \
        (f"attempt {len(tried) + 1}: {last}" if tried else last)


def fifo(probe):
    yield from settle(probe)
    default = DOCUMENTED["fifo_frames"]
    fill1, round1, start_us, tried1 = yield from held_round(probe, _round1)
    if fill1.final is None:
        return Finding("fifo_frames", default, None, _by_hand(f"round 1: {_attempts(tried1, fill1.evidence)}"), UNSURE,
                       {"round_1": fill1.hold})
    final1, evidence1 = fill1.final, _attempts(tried1, fill1.evidence)
    accepted1 = _accepted(round1, final1, start_us)
    if accepted1 is None:
        return Finding("fifo_frames", default, None,
                       _by_hand(f"round 1: the arm ended at PWM {final1} µs, a value never sent"), UNSURE)
    if accepted1 == 0:
        return Finding("fifo_frames", default, 0, f"round 1: {evidence1}: not one frame behind the delay was accepted",
                       fill1.confidence)
    block = (accepted1 - 1) // BLOCK
    lead_count = block * BLOCK
    tail = min(BLOCK, MAX_FRAMES - lead_count)
    fill2, round2, start2_us, tried2 = yield from held_round(probe, _round2(lead_count, tail), fill1.pace)
    holds = {"round_1": fill1.hold, "round_2": fill2.hold}
    if fill2.final is None:
        return Finding("fifo_frames", default, None, _by_hand(f"round 2: {_attempts(tried2, fill2.evidence)}"), UNSURE,
                       holds)
    final2, evidence2 = fill2.final, _attempts(tried2, fill2.evidence)
    accepted2 = _accepted(round2, final2, start2_us)
    if accepted2 is None or not lead_count < accepted2 <= lead_count + tail:
        return Finding("fifo_frames", default, None,
                       _by_hand(f"round 1 put the last frame accepted in {lead_count + 1}…{lead_count + tail}, round 2 "
                                f"at {accepted2}: the arm is not consistent"), UNSURE, holds)
    capacity = accepted2  # fifo_frames: the frames accepted behind the one executing
    confidence = SURE if SURE == fill1.confidence == fill2.confidence else LIKELY
    evidence = (f"round 1: {evidence1} (block {lead_count + 1}…{lead_count + tail}); round 2: {evidence2}: the last "
                f"frame accepted was #{accepted2} behind the delay, so the connector holds {capacity} frames behind the one executing")
    details = {"frames_accepted_behind_delay": accepted2, "frames_written": MAX_FRAMES, **holds}
    if accepted2 == MAX_FRAMES:
        return Finding("fifo_frames", default, capacity,
                       evidence + f" or more (all {MAX_FRAMES} frames written were accepted)", LIKELY,
                       {**details, "at_least": True})
    return Finding("fifo_frames", default, capacity, evidence, confidence, details)


def _current_pwm(probe) -> int:
    got = probe.seen.agreed(PauseStatus.KIND, probe.now_s - 1.0, lambda f: f.pwm_us)
    return got[1] if got is not None else probe.known.pwm_us
