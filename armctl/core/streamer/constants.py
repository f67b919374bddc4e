"""The streamer's numbers: what the document says, what it leaves open (read from the profile
where one is given; these are the document's reading), and the tolerances of the evidence.

Strategy: constants only, with the reason each has its value; every part of the streamer reads
them from here (one home per number).
"""

from __future__ import annotations

from ..armstate import ROTATION_S
from ..protocol import STATUS_PERIOD_S

DEFAULT_LEAD_S = 2.0
# Frames kept free in the FIFO below its capacity: one for a frame the arm may still count while
# executing it, the rest for what no model foresees.
CAPACITY_MARGIN_FRAMES = 4


def limit_frames(capacity: int, margin: int = CAPACITY_MARGIN_FRAMES) -> int:
    """Frames that may wait in the connector unconfirmed (the gate's bound, and the estimate's):
    its ``capacity`` less the ``margin`` kept free — but at most half of a connector under twice
    the margin (a probe may measure 4 frames: the whole margin would leave none to stream with)
    — and at least 2, an arc's two frames (with 1 a job with an arc never ended: its second frame
    waited for the first's room; the profile's ``fifo_frames`` starts at 3: core/limits.py)."""
    return max(capacity - min(margin, capacity // 2), 2)

# The time bound assumes the arm is never more than ``speed_tolerance`` times slower than the model,
# whose durations already include the profile's speed_factor: the slowest arm allowed for is
# relative to the configured one.  That is a hypothesis about the arm the document leaves open, so
# it is the profile's ``[connector] speed_tolerance`` (the document-level 2.0 below; ``armctl
# probe`` measures it): these constants are the document's reading, for whoever has no profile.
SLOWEST_ARM_FACTOR = 2.0
# The other side of the same trust: the arm is never more than 1 / this faster than the model.
# A frame the arm skipped (dropped by a full FIFO, cleared) shows as the arm getting somewhere
# sooner than the frames in between could take even at that pace (see ``losses.Losses``).
# Symmetric to the slowest factor (1 / speed_tolerance): the matrix of arms (speed_factor 0.7…2.0
# against a profile of 1.0) stays inside the document's 2.0, so a good arm never raises the alarm.
FASTEST_ARM_FACTOR = 1 / SLOWEST_ARM_FACTOR
# Added to the time between the two sightings that frame a suspected gap: a status frame is
# sampled up to a period before it is read, and each sighting is timed to one period.
LOSS_SLACK_S = 2 * STATUS_PERIOD_S
# Frames kept for the loss check (how far back a sighting's frame can be looked up).
RECENT_SENT_FRAMES = 512
# The measured pace (the arm's seconds ÷ the model's, see ``Streamer.pace``): a sample spans at
# least this much model time on one segment (a status sighting is timed to a few ms), the pace is
# the largest of the last PACE_SAMPLES samples (the slower reading wins), and at most PACE_MAX
# (a pause in arrival mode freezes a segment: that is no pace).
PACE_MIN_SPAN_S = 0.25
PACE_SAMPLES = 4
PACE_MAX = 4.0
# From this pace on the lead follows the frames at the arm's pace, not the estimate's
# (``Estimate.arm_ends``); below it the two differ by less than a sighting's timing (a status
# period in a quarter second: a nominal arm measures 1.000-1.003).
PACE_FOLLOWED = 1.02
# Latest a frame may reach the connector after its last byte left the host (USB adapters,
# kernel buffers), and slack per frame for the controller's own handling at the document-level
# tolerance (SLOWEST_ARM_FACTOR); a tolerance t allows (t − 1) / (SLOWEST_ARM_FACTOR − 1) of it
# (``frame_slack_s``): the probe that measures t bounds a frame's start delay with it.
ARRIVAL_SLACK_S = 0.05
FRAME_SLACK_S = 0.02
# How close a reported value must be to a path to count as evidence (the status resolution is
# 0.1 mm and 0.01 deg; the rest covers the moment between sampling and reading).
POSITION_TOLERANCE_MM = 0.5
JOINT_TOLERANCE_DEG = 0.2
# A joint segment's X/Y/Z trace is matched against 16 chords of its forward kinematics; the chords
# cut corners, so its tolerance adds this many times the largest chord-midpoint deviation.
JOINT_TRACE_SLACK = 2.0
JOINT_TRACE_FRACTION = 1 / 16  # how far along a joint segment one chord of its trace reaches
# With the next command known, its own duration counts against the lead; but a frame is always
# allowed once no more than this (or the lead, if shorter) is queued, so the arm never waits for
# a move longer than the lead.
FEED_AHEAD_S = 0.5
# An observation is matched against this many of the oldest pending frames and as many around the
# estimate's frame, so its cost does not grow with the queue (see ``Sightings.search``).
SCAN_WINDOW_FRAMES = 16
# A straight move whose refusal no sign of loss can see needs reports on its path to count as run
# (``Ledger.prove_ran``) if it lasts this long by the model: four position reports, so two past its
# start even with one lost.  A shorter one refused shows no gap and no standing either (its time at
# the fastest pace is within a report's timing, and the arm runs on at once), so nothing could prove
# it ran: it needs the reports' proof only where the plan itself foresees the refusal — a target the
# profile's kinematics put out of the arm's reach (``Sightings.may_refuse``), wherever it stands.
RUN_PROOF_MIN_S = 4 * ROTATION_S
# With kinematics not verified on the arm, where a joint move really ends may be this share of the
# reach away from where the profile's forward kinematics put it (a link 10 % off): the time bound of
# the Cartesian move that starts there allows for that much more path.
UNVERIFIED_FK_SHARE = 0.1


def frame_slack_s(slowest_factor: float) -> float:
    """The time bound's slack per frame for an arm up to ``slowest_factor`` times slower than the
    model: FRAME_SLACK_S at the document's SLOWEST_ARM_FACTOR, in proportion to the factor's
    excess over 1 (an arm probed to run as its profile says leaves no room for unmodelled handling
    either: the probe's timed moves bound a frame's start delay with the same margin)."""
    return FRAME_SLACK_S * max(0.0, slowest_factor - 1.0) / (SLOWEST_ARM_FACTOR - 1.0)
