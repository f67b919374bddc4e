"""The connector's capacity, exactly, with frames that do not move the arm.

Strategy: a long delay (G4) keeps the arm busy while PWM-only frames (a joint move to the
joints the arm reports, a new PWM) are written behind it at the line rate, more than the
connector can hold.  Nothing leaves the FIFO while the delay runs, so it accepts exactly
``fifo_frames`` of them — the frames it holds behind the one the arm executes (whether the
executing delay keeps a slot of its own is not observable; this number is) — and drops the rest.  When the delay ends the arm runs the accepted frames in
order; the PWM it finally reports (status kind 4) names the last frame accepted.

A PWM change takes the servo time (``timing.pwm_change_s`` on the model; 0.3 s), so giving
all 300 frames distinct values would cost minutes.  Two rounds instead: round 1 changes the
value every ``BLOCK`` frames (the final value names a block of 16); round 2 repeats the value
the arm now holds (a frame that changes nothing takes no time) up to that block and gives each
frame in it its own value.  The end of a round is seen, not assumed: the reported PWM has not
changed for ``max(QUIET_S, 3 ×`` the longest step seen between new values``)``.  A round whose PWM
changed before its last frame landed (the delay ended early) proves nothing: unsure.
"""

from __future__ import annotations

import math

from ..protocol import PWM_RANGE_US, Delay, PauseStatus
from .plan import AGREEING_FRAMES, LIKELY, SURE, UNSURE, Finding, Send, Wait
from .steps import DOCUMENTED, QUIET_S, pwm_frame, settle

MAX_FRAMES = 300  # fillers written per round: the document's 200 and half again
BLOCK = 16
STEP_US = 5  # PWM step between values: the gripper barely moves (≤ 100 µs from where it was)
FILL_MARGIN_S = 1.0  # the delay outlasts the last filler's landing by this much
ROUND_LIMIT_S = 60.0  # a round that has not settled by then is given up


def _changes(probe, since_s: float) -> list[tuple[float, int]]:
    """(time, PWM) of each kind-4 frame since ``since_s`` whose PWM differs from the frame before.
    Single frames, not agreed runs: while the FIFO drains a value may last less than two frames
    of its kind; a corrupted frame only adds a change, which makes the wait longer, not wrong."""
    changes, previous = [], None
    for t, frame in probe.seen.since(PauseStatus.KIND, since_s):
        if previous is not None and frame.pwm_us != previous:
            changes.append((t, frame.pwm_us))
        previous = frame.pwm_us
    return changes


def _direction(start_us: int, span_us: int) -> int:
    return 1 if start_us + span_us <= PWM_RANGE_US[1] else -1


def fill_round(probe, values: list[int], start_us: int):
    """Delay, then ``values`` as PWM-only frames; returns (last value reported, evidence) or
    (None, why)."""
    count = len(values)
    delay_s = math.ceil(((count + 1) * probe.frame_s + FILL_MARGIN_S) * 10) / 10
    delay_landed_s = yield Send(Delay(delay_s * 1000))
    end_s = delay_landed_s + delay_s
    probe.known.busy_until_s = end_s
    last_landed_s = delay_landed_s
    for value in values:
        last_landed_s = yield Send(pwm_frame(probe, value))
    deadline_s = end_s + ROUND_LIMIT_S

    # Frames that repeat the PWM show nothing while they run: until a change is seen, allow them
    # a frame time each (an arm slower than that could not keep up with the line anyway).
    silent_s = QUIET_S + sum(1 for a, b in zip([start_us, *values], values) if a == b) * probe.frame_s

    def settled() -> bool:
        times = [t for t, _ in _changes(probe, end_s - 1.0) if t >= end_s]
        if not times:
            return probe.now_s - end_s >= silent_s
        gaps = [b - a for a, b in zip([end_s, *times], times)]
        return probe.now_s - times[-1] >= max(QUIET_S, 3 * max(gaps))

    yield Wait(deadline_s, settled)
    sent = set(values)
    early = [(t, v) for t, v in _changes(probe, delay_landed_s) if t < last_landed_s and v in sent and v != start_us]
    if len(early) >= AGREEING_FRAMES:
        return None, (f"the PWM changed {early[0][0] - delay_landed_s:.2f} s into the {delay_s:g} s delay, before the "
                      "last frame landed: the delay did not hold the arm")
    final = probe.seen.agreed(PauseStatus.KIND, end_s, lambda f: f.pwm_us)
    if not settled() or final is None:
        return None, f"the PWM had not settled {ROUND_LIMIT_S:g} s after the delay"
    final = final[1]
    probe.known.busy_until_s = probe.now_s
    return final, f"{count} PWM-only frames behind a {delay_s:g} s delay; the arm ended at PWM {final} µs"


def _accepted(values: list[int], final: int, start_us: int) -> int | None:
    """How many of ``values`` (in order) were accepted, if the arm ends at ``final``."""
    indexes = [k + 1 for k, v in enumerate(values) if v == final]
    if indexes:
        return max(indexes)
    return 0 if final == start_us else None


def fifo(probe):
    yield from settle(probe)
    known = probe.known
    default = DOCUMENTED["fifo_frames"]
    start_us = _current_pwm(probe)
    blocks = math.ceil(MAX_FRAMES / BLOCK)
    direction = _direction(start_us, STEP_US * (blocks + 1))
    round1 = [start_us + direction * STEP_US * (k // BLOCK + 1) for k in range(MAX_FRAMES)]
    final1, evidence1 = yield from fill_round(probe, round1, start_us)
    if final1 is None:
        return Finding("fifo_frames", default, None, f"round 1: {evidence1}", UNSURE)
    accepted1 = _accepted(round1, final1, start_us)
    if accepted1 is None:
        return Finding("fifo_frames", default, None, f"round 1: the arm ended at PWM {final1} µs, a value never sent", UNSURE)
    if accepted1 == 0:
        return Finding("fifo_frames", default, 0, f"round 1: {evidence1}: not one frame behind the delay was accepted", SURE)
    block = (accepted1 - 1) // BLOCK
    lead_count = block * BLOCK
    direction2 = _direction(final1, STEP_US * (BLOCK + 1))
    tail = min(BLOCK, MAX_FRAMES - lead_count)
    round2 = [final1] * lead_count + [final1 + direction2 * STEP_US * (k + 1) for k in range(tail)]
    final2, evidence2 = yield from fill_round(probe, round2, final1)
    if final2 is None:
        return Finding("fifo_frames", default, None, f"round 2: {evidence2}", UNSURE)
    accepted2 = _accepted(round2, final2, final1)
    if accepted2 is None or not lead_count < accepted2 <= lead_count + tail:
        return Finding("fifo_frames", default, None,
                       f"round 1 put the last frame accepted in {lead_count + 1}…{lead_count + tail}, round 2 at "
                       f"{accepted2}: the arm is not consistent", UNSURE)
    capacity = accepted2  # fifo_frames: the frames accepted behind the one executing
    evidence = (f"round 1: {evidence1} (block {lead_count + 1}…{lead_count + tail}); round 2: {evidence2}: the last "
                f"frame accepted was #{accepted2} behind the delay, so the connector holds {capacity} frames behind the one executing")
    details = {"frames_accepted_behind_delay": accepted2, "frames_written": MAX_FRAMES}
    if accepted2 == MAX_FRAMES:
        return Finding("fifo_frames", default, capacity,
                       evidence + f" or more (all {MAX_FRAMES} frames written were accepted)", LIKELY,
                       {**details, "at_least": True})
    return Finding("fifo_frames", default, capacity, evidence, SURE, details)


def _current_pwm(probe) -> int:
    got = probe.seen.agreed(PauseStatus.KIND, probe.now_s - 1.0, lambda f: f.pwm_us)
    return got[1] if got is not None else probe.known.pwm_us
