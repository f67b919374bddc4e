"""The pacing core: when may the next frame be written to an arm that never acknowledges?

Strategy: pure — status frames, writes and ``now`` come in as arguments; decisions come out.
The connector holds at most ``fifo_frames`` frames behind the one executing (the profile's
``[connector]`` table; 200 by the document) and silently drops the rest, and the arm says only
where it is.  What the document leaves open is read from the profile, never assumed here:
``fifo_frames`` (the capacity), ``speed_factor`` (in the motion model's durations),
``status_xyz_frame`` (robot-frame X/Y/Z are turned into the worktable frame of the segment they
are matched against) and ``kinematics_verified`` (below).  So for every frame written the streamer keeps its planned ``Segment`` (the shared
motion-time model), the moment its last byte left the wire, and two views of the arm:

* a **lower bound of frames consumed**, advanced only on evidence:
  - *position*: a reported position (or joint half, for joint and still segments) lies on the
    path of segment k, and on no earlier segment still pending, so every frame before k has
    finished and left the FIFO.  The earliest candidate counts (a point on several pending
    paths — repeated targets — proves only the first).  An observation moves the bound only
    when the one before it in the same stream agrees (the smaller of the two counts), so one
    corrupted status frame can never move it.  Evidence comes from what the arm itself reports:
    X/Y/Z for Cartesian frames, joints for joint frames.  Only with ``kinematics_verified`` is
    a joint move's X/Y/Z trace matched (against chords of its forward kinematics, with a
    tolerance widened by how far the chords cut corners), and a still frame matched on the half
    of its pose that the profile's kinematics computed; without it an unverified FK/IK never
    decides what the arm consumed.  Joint halves prove nothing while a Cartesian segment is
    pending before them.
    An arc's G300 is held by the arm until its G301 has landed and finishes with it: evidence
    of the arc never confirms its G300 alone.  For a flat cost per status frame the search
    covers the oldest pending frames and a window around the estimate's frame (the rest only
    when neither matches); a match beyond an unsearched gap proves only the gap's first frame.
  - *time*: frames that leave no trace in the position (delays, M codes, control frames,
    PWM-only and attitude-only moves) are confirmed once even an arm ``slowest_factor`` times
    slower than the model would have finished them (the model's durations already include the
    configured ``speed_factor``, so the factor allows for an arm that much slower than its
    profile says; it is the profile's ``[connector] speed_tolerance``, 2 by the document's
    silence, measured by ``armctl probe``; each frame adds ``frame_slack_s``, 20 ms at 2 and
    in proportion to the factor's excess over 1), counting only time the arm was seen
    running (kind-4 status), so a pause, or silence about the pause state, stops that clock
    and a resume pushes every pending deadline back by the whole pause.  The deadlines form a
    chain from frame to frame; agreeing evidence that frame k has begun restarts the chain at
    k (else it would drift ahead by the slowest factor for as long as the arm is kept busy),
    from the least fraction of k's path both agreeing observations put the arm at (so a frame
    seen at its end is confirmed soon after, not a whole slow-arm duration later).  A Cartesian
    move from a joint move's end on an arm whose kinematics are not verified may be longer than
    planned: a line by at most its start's error, allowed for; an arc without bound, so time
    never confirms it (``_unknown_start_s``) — a later frame's sighting or the arm at rest does;
    nor the first move that sets E0/E1, which no status reports: from where they stood, its time
    may be any (``_moves_e_from_the_start``; no pace is measured on it either).
  Lost or corrupted status frames can only hold the bound back, i.e. make it more careful.
* an **estimate** of when each frame ends, from the model, re-anchored on every observation:
  each candidate segment says the arm is now within a window of that segment's time (a short
  one on a path that moves, the whole segment on one that does not move what was observed);
  the window nearest the estimate wins and the estimate moves by the least that puts ``now``
  in it.  So a still frame never pushes the estimate while the estimate agrees with it, and
  an arm standing still (paused, or slower than the model) holds the estimate back.

A frame may be written only once the previous frame has left the wire — or, on a wall clock,
at most ``write_ahead_s`` before (``JobRunner``: the host's own wake-up may be late, and a frame
waiting in the OS buffer starts the moment the line is free, which is when the model has it start
anyway; the lead and the FIFO bound are judged at the write, so an early frame lands no earlier
than the model says) — writes are paced to the line, so no OS buffer hides seconds of frames —
and while both hold:
(a) frames written − lower bound < capacity − margin (never overflow the FIFO, whatever the
    estimate says);
(b) the estimated motion waiting behind the frame in progress — including the new frame, when
    ``next_write_time`` is told which it is — is at most ``lead_s`` **in the arm's seconds**, so
    an abort (a pause frame queued behind everything, H5) leaves the arm at most the lead plus
    the move in progress.  Model seconds become the arm's through the configured speed_factor
    (in the model) and the measured ``pace``: the arm's observed time ÷ the model's along one
    segment, from two agreeing sightings on it at least ``PACE_MIN_SPAN_S`` of model time apart
    (the largest of the last few, never below 1).  From a pace of ``PACE_FOLLOWED`` on, the
    frames are followed at that pace from where a sighting inside a moving path last pinned the
    arm (``_arm_ends``), since the estimate runs at the model's pace through frames no sighting
    re-times.  A frame is also allowed once no more than ``FEED_AHEAD_S`` (or the lead) of the
    arm's seconds is queued in all, so the arm is never starved of a move longer than the lead
    by itself — and, behind a first pending frame not yet begun (written ahead), only once it
    begins.  The pace shapes only this rule (and ``queued_seconds``): the lower bound never
    reads it.
(c) with ``control_frames = "arrival"`` a control frame (POSE, PROGRAM, G54, a pause toggle…)
    acts the moment it lands, ahead of everything queued: one in a job is written only once the
    lower bound says every frame before it has finished, so the arm runs the job in its order.

Repeated targets (a zig-zag, back and forth, a closed path) are what position cannot prove:
every report lies on every pending path through that point, so it proves only the oldest
pending frame, and the rest is confirmed by time.  At the document's 2x (+ 20 ms a frame) a
10 ms move is confirmed every 40 ms, so frames consumed but unproven grow by ~75 a second
until the FIFO bound throttles the job to the proof's rate (``armctl bench``'s ``backforth``:
2.98x its physical bound).  Two ways were weighed (issue 13):
  - *order*: a direction reversal seen between sightings proves one more frame began — but
    status positions come every 90 ms while such an arm turns every 10 ms, so order is aliased:
    one frame proven where nine ran.  Not used.
  - *timing*, chosen: the hypothesis behind the time bound is a setting of the arm profile
    (``speed_tolerance``) that the probe measures (speed_factor to ±0.01 on its timed moves, and
    the moves' start delay) and writes with a margin (at least 5 %).  Unproven frames then grow
    at 1 − d / (d·t + slack) of the arm's rate — 13 a second for 10 ms moves at 1.05 — so 1,000
    of them never fill the FIFO bound (196) with unproven frames: the job reaches its physical
    bound.  The lag still grows with a job's length (about 15 s of uninterrupted 10 ms
    back-and-forth throttles again); only a position on one pending path re-anchors it.
  The hypothesis is checked as the job runs, twice.  A measured ``pace`` (the arm slower than
  its profile's speed_factor) widens the bound to ``speed_tolerance × pace`` for every pending
  frame and every later one (``_widen_time_bound``: only ever more careful), so an arm 1.3x or
  2x slower than a profile probed at 1.05 drops nothing once one frame long enough to time has
  run.  And pairs of agreed sightings along one frame (a status period of slack at each end, one
  corrupted report cannot decide) that prove the arm slower than the tolerance, on no later
  frame through the same point, end the job "frames may have been lost", never done, when time
  confirmed frames at a narrower factor (``check_time_bound``): frames confirmed before any
  pace could be measured (delays, then a long move) may have been overrun.

What the summary may claim is data too: every frame consumed counts as confirmed by the arm's
reports, by time alone, or as gone from the FIFO unseen (``confirmed_by_reports`` /
``confirmed_by_time`` / ``confirmed_unseen``): a report on a later frame proves a frame left the
FIFO, and that it ran only where the caller knows the FIFO holds every frame the capacity rule
lets in (``fifo_holds_all``: a dropped frame leaves too, and the frame after it runs along its
path when they lie in a row) and no RESET CONNECTOR may have cleared it (``may_be_cleared``,
which time never confirms either); the arm at rest at the last frame's own target proves that
one (``ran_at_rest``).  And ``losses``
holds each sign of loss with its evidence: two agreed sightings of one stream, the later at
least at frame k, the earlier at most at the latest frame its report may lie on (no later than
the latest the later report may lie on: the arm runs its frames in order), between which the
arm could not have run the frames in between even ``speed_tolerance`` times faster than
the model.  After ``cleared`` (a RESET CONNECTOR acting as it lands) time confirms nothing.

Why it decided is data too, for whoever drives it (armctl/runner.py logs it with ``-v``):
``next_write_time`` leaves the binding constraint in ``write_reason`` (``WaitReason``: the FIFO's
capacity, the lead, the wire, or none), and each advance of the lower bound leaves its evidence
in ``bound_evidence`` (``Evidence``: position, joints, time, the arm at rest at the end).

The lead is the knob between a prompt stop and the line's pace: behind a move longer than the
lead, short line-bound moves wait until the queue behind it is within the lead, so the line
idles for most of that move (``armctl bench``'s ``longfirst`` row shows the cost; a longer
``--lead`` removes it).  Writing them earlier would leave more than the lead queued behind the
move in progress, so an abort near its end (or a feed override, whose effect shows within the
lead — in either control-frame mode) would wait longer than the lead after it: the stop bound
is not traded for speed.  The idle is exactly the lead's: at 2 s, 50 of the 40 ms moves wait
behind the 4.7 s move and the line has nothing to send for the rest of it (docs/bench.md).
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections import deque
from dataclasses import dataclass
from enum import StrEnum

from .motion import ArmPose, MotionModel, Planner, Segment, distance_to_path
from .protocol import (
    CONTROL_COMMANDS,
    ArcEnd,
    ArcStart,
    DEFAULT_BAUD,
    STATUS_PERIOD_S,
    STATUS_ROTATION,
    Command,
    JointsHighStatus,
    JointsLowStatus,
    PauseStatus,
    PositionStatus,
    ResetConnector,
    StatusFrame,
    frame_seconds,
)

DEFAULT_LEAD_S = 2.0
# Frames kept free in the FIFO below its capacity: one for a frame the arm may still count while
# executing it, the rest for what no model foresees.
CAPACITY_MARGIN_FRAMES = 4
# The time bound assumes the arm is never more than ``speed_tolerance`` times slower than the model,
# whose durations already include the profile's speed_factor: the slowest arm allowed for is
# relative to the configured one.  That is a hypothesis about the arm the document leaves open, so
# it is the profile's ``[connector] speed_tolerance`` (the document-level 2.0 below; ``armctl
# probe`` measures it): these constants are the document's reading, for whoever has no profile.
SLOWEST_ARM_FACTOR = 2.0
# The other side of the same trust: the arm is never more than 1 / this faster than the model.
# A frame the arm skipped (dropped by a full FIFO, cleared) shows as the arm getting somewhere
# sooner than the frames in between could take even at that pace (see ``Streamer.losses``).
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
# (``Streamer._arm_ends``); below it the two differ by less than a sighting's timing (a status
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
ROTATION_S = len(STATUS_ROTATION) * STATUS_PERIOD_S
# An observation is matched against this many of the oldest pending frames and as many around the
# estimate's frame, so its cost does not grow with the queue (see ``Streamer._scan``).
SCAN_WINDOW_FRAMES = 16
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


class WaitReason(StrEnum):
    """What held the last write back (``Streamer.write_reason``)."""

    READY = "ready"  # nothing: the frame may go now
    CAPACITY = "capacity"  # rule (a): the FIFO bound is reached; only new evidence allows a write
    LEAD = "lead"  # rule (b): the motion waiting behind the move in progress fills the lead
    WIRE = "wire"  # the previous frame is still leaving the host at the line's rate
    IN_ORDER = "in order"  # rule (c): a control frame acting on arrival waits until the queue is known done


class Evidence(StrEnum):
    """What last advanced the lower bound of frames consumed (``Streamer.bound_evidence``)."""

    POSITION = "position"  # two agreeing X/Y/Z reports on the path of a later frame
    JOINTS = "joints"  # two agreeing joint-half reports on a later joint or still frame
    TIME = "time"  # even an arm slowest_factor times slower than the model has finished them
    AT_REST = "at rest"  # the caller saw the arm at rest at the last target (confirm_all_done)


@dataclass
class SentFrame:
    """A frame on its way to, in, or through the connector's FIFO."""

    index: int
    command: Command
    segment: Segment
    tag: object  # the caller's reference, e.g. the script line
    wire_end_s: float  # its last byte left the host
    est_end_s: float = 0.0  # the estimate: when the arm finishes it
    certain_end_s: float = 0.0  # the time bound: it has surely finished by then (arm-running time)
    chain_end_s: float = 0.0  # the time bound as a chain of frames (a G300's certain end is its G301's)
    group_index: int = -1  # the first frame of its group: an arc's G301 finishes with its G300
    xyz_tolerance_mm: float = POSITION_TOLERANCE_MM  # how near its path an X/Y/Z must be to match
    # False for a move that starts where only the profile's unverified kinematics put an earlier
    # frame of the job (a Cartesian move at a joint move's end, a joint move at a Cartesian one's):
    # the arm's path is not the planned one, and it may pass within tolerance of the next frame's
    # path, so a sighting may count on it (the earliest claim) but never past it; the time bound,
    # with ``_unknown_start_s``'s allowance, confirms a line or a joint move (never an arc).
    path_known: bool = True
    unknown_start_s: float = 0.0  # ``Streamer._unknown_start_s`` of its segment, reckoned once at write
    motion_before_s: float = 0.0  # the model's motion time of every frame written before it
    # ... of those whose length the plan knows: a move whose start only the profile's unverified
    # kinematics know (``unknown_start_s``) may be any shorter, so the loss checks' least motion
    # counts it as none
    sure_before_s: float = 0.0
    sure_s: float = 0.0  # its own share of ``sure_before_s`` for the frames after it (0 with an allowance)
    timing_known: bool = True  # False: its time may be any (``Streamer._moves_e_from_the_start``): no pace from it
    seen: bool = False  # the arm at rest at its target proved it ran (``Streamer.ran_at_rest``)
    may_be_cleared: bool = False  # queued when a RESET CONNECTOR may have cleared it (``Streamer.cleared``)


@dataclass(frozen=True)
class Observation:
    """Where the arm was seen: a segment index and how far along it (0…1)."""

    index: int
    fraction: float
    at_s: float


class Streamer:
    """Decides when the next frame may be written; see the module docstring."""

    def __init__(
        self,
        model: MotionModel,
        start: ArmPose,
        *,
        lead_s: float = DEFAULT_LEAD_S,
        capacity: int | None = None,
        margin: int = CAPACITY_MARGIN_FRAMES,
        baud: int = DEFAULT_BAUD,
        slowest_factor: float | None = None,
        now: float = 0.0,
        write_ahead_s: float = 0.0,
    ) -> None:
        """``capacity``: frames the connector holds behind the one executing (None: the profile's
        ``[connector] fifo_frames``); ``slowest_factor``: how many times slower than the model the
        arm may run (None: the profile's ``[connector] speed_tolerance``); ``write_ahead_s``: how
        long before the line is free the next frame may be handed to the port (a wall-clock host's
        buffer against its own wake-up jitter; 0 in virtual time, where nobody is late)."""
        if lead_s <= 0:
            raise ValueError("lead_s must be greater than 0")
        self.planner = Planner(model, start)
        connector = model.profile.connector
        self.kinematics_verified = connector.kinematics_verified
        self._unknown_start_mm = UNVERIFIED_FK_SHARE * model.profile.workspace.reach_mm
        self.control_on_arrival = connector.control_on_arrival
        self.reports_robot_xyz = connector.reports_robot_xyz
        self.lead_s = lead_s
        self.limit_frames = (connector.fifo_frames if capacity is None else capacity) - margin
        self.frame_s = frame_seconds(baud)
        self.slowest_factor = connector.speed_tolerance if slowest_factor is None else slowest_factor
        self._tolerance = self.slowest_factor  # relative to the measured pace (``_measure_pace``)
        self._least_factor_confirmed: float | None = None  # the factor in force when time first confirmed a frame
        self.fastest_factor = 1 / self.slowest_factor  # the loss checks: the arm at most this much faster
        self.frame_slack_s = frame_slack_s(self.slowest_factor)
        self.pending: deque[SentFrame] = deque()  # frames not yet known consumed, oldest first
        self.sent = 0
        self.consumed_lower_bound = 0
        self.wire_free_s = now
        self.write_ahead_s = write_ahead_s
        # Where a sighting last pinned the arm on the estimate: (time, frame, model s of it left);
        # ``_arm_ends`` follows the frames at the measured pace from there
        self._pin: tuple[float, int, float] | None = None
        self._last_candidate: dict[str, int | None] = {}
        self._last_fraction: dict[str, float | None] = {}  # the least fraction on that candidate
        self._last_done_tag = None
        # Arm-running clock for the time bound: seconds the arm was certainly not paused.
        self._running_seen_s: float | None = None
        self._paused = False
        self._pause_began_s = now
        self.status_frames = 0
        self._peeked: tuple[Command, Segment] | None = None
        self._certain_tail_s = 0.0  # the time bound of the last frame written (even a G300's)
        self._cartesian: deque[int] = deque()  # indexes of pending Cartesian frames (joint halves stop there)
        self._blind: deque[int] = deque()  # indexes of pending frames whose X/Y/Z cannot be judged (positions stop there)
        self._joints_unknown: deque[int] = deque()  # ... joint frames whose path is not the planned one (joint halves stop past them)
        self.write_reason = WaitReason.READY  # why next_write_time answered as it did
        self.next_frame_motion_s = 0.0  # the motion of the frame next_write_time was asked about
        self.bound_evidence: Evidence | None = None  # what last advanced consumed_lower_bound
        self.pace = 1.0  # the arm's seconds ÷ the model's, measured (see the module docstring)
        # Bumped whenever an observation changes what ``next_write_time`` reads besides the
        # lower bound (the estimate's end times, the pace): a status frame that moved neither
        # cannot change when the next frame may go (``Job.receive_status``'s news).
        self.plan_changes = 0
        self._pace_samples: deque[float] = deque(maxlen=PACE_SAMPLES)
        self._pace_from: dict[str, tuple[int, float, float]] = {}  # stream → (index, model s, now)
        # What proves each frame consumed (the summary's honesty): the arm's reports (a position
        # or joints on a later frame's path, the arm at rest at the last target) or time alone.
        self.confirmed_by_reports = 0
        self.confirmed_unseen = 0  # gone from the FIFO by a report, not proven run (``_consume_one``)
        # Whether a frame gone from the FIFO has run: true when the connector holds every frame the
        # capacity rule lets in (the caller knows: a probed FIFO size, armctl/job.py's fifo_proven);
        # else a frame a full FIFO dropped leaves it as well.
        self.fifo_holds_all = True
        self._reset_index: int | None = None  # the last RESET CONNECTOR written (``wrote``)
        self._e_known = False  # a move has set E0/E1 since the start (``_moves_e_from_the_start``)
        self._time_proves = True  # False once the FIFO may have been cleared (``cleared``)
        self.confirmed_by_time = 0
        self.motion_sent_s = 0.0  # the model's motion time of every frame written
        self.sure_motion_sent_s = 0.0  # ... less the frames that may be any shorter (``SentFrame.sure_before_s``)
        # Signs of loss (``losses``): each a sentence with its evidence; ``first_suspect_index``
        # is the earliest frame that may not have run (None: no sign).
        self.losses: list[str] = []
        self.first_suspect_index: int | None = None
        self.first_time_only_index: int | None = None  # the first frame confirmed by time alone
        self._recent_sent: deque[SentFrame] = deque(maxlen=RECENT_SENT_FRAMES)
        self._reversed_on: int | None = None  # the finished frame the last position report lay on (reversal check)
        self._span_from: dict[str, tuple[int, float, float]] = {}  # stream → (index, least model s, at): first pair on a frame
        self._span_last: dict[str, tuple[int, float, float, float]] = {}  # stream → (index, model s lo, hi, at): last sighting
        self._too_slow: tuple[float, SentFrame] | None = None  # the arm seen slower than slowest_factor on a frame
        self.slowest_proven = 0.0  # the most ``_too_slow`` was in this job (a stale speed_factor: armctl/calibration.py)
        self._sighting: dict[str, tuple] = {}  # stream → (index, at_s, could_be_on) of its last agreed sighting
        # ``_time_at``'s memory: the times of fractions along the segment last asked about
        self._times_segment: Segment | None = None
        self._times: dict[float, float] = {}

    # --- writing ----------------------------------------------------------------------------

    @property
    def frames_in_flight_bound(self) -> int:
        """Frames written and not known consumed: an upper bound of the FIFO's occupancy."""
        return self.sent - self.consumed_lower_bound

    def queued_seconds(self, now: float) -> float:
        """Estimated motion queued ahead of the arm: when it will finish everything, from now —
        on an arm measured slower than the model, the later of the estimate and the frames
        followed at its pace (``_arm_ends``: the estimate may have run ahead of the arm)."""
        if not self.pending:
            return 0.0
        ends = self._arm_ends()
        tail_s = self.pending[-1].est_end_s if ends is None else max(ends[-1], self.pending[-1].est_end_s)
        return max(0.0, tail_s - now)

    def waiting_seconds(self, now: float) -> float:
        """Estimated motion in frames the arm has not begun yet: ``queued_seconds`` without the
        rest of the frame in progress.  This is what the lead bounds."""
        if not self.pending:
            return 0.0
        tail_s = self.pending[-1].est_end_s
        current_end_s = next((sent.est_end_s for sent in self.pending if sent.est_end_s > now), tail_s)
        return max(0.0, tail_s - max(now, current_end_s))

    def next_write_time(self, now: float, command: Command | None = None) -> float | None:
        """The earliest time ≥ now the next frame may be written if no news arrives; None while
        only new evidence can allow it (the FIFO bound is reached).

        The lead bounds the motion waiting behind the frame in progress (``waiting_seconds``):
        after an abort the arm finishes the move it is on plus at most the lead.  With
        ``command`` (the frame about to be written) its own duration counts too, so the bound
        holds after the write; without it, it is checked before the write (the queue may then
        exceed it by the frame just written).  Either way a frame is always allowed once no
        more than ``FEED_AHEAD_S`` (or the lead, if shorter) is queued in all, so the arm never
        waits for a move that is longer than the lead by itself."""
        if self.frames_in_flight_bound + 1 > self.limit_frames:
            self.write_reason = WaitReason.CAPACITY
            return None
        wire_ok_at = self.wire_free_s - self.write_ahead_s  # handed over early, it still starts when the line is free
        if not self.pending:
            self.write_reason = WaitReason.WIRE if wire_ok_at > now else WaitReason.READY
            return max(now, wire_ok_at)
        if self.control_on_arrival and isinstance(command, CONTROL_COMMANDS):
            self.write_reason = WaitReason.IN_ORDER  # rule (c): only evidence lets it go
            return None
        duration_s = 0.0 if command is None else self._plan(command).duration_s
        self.next_frame_motion_s = duration_s
        ends = self._arm_ends()
        if ends is None:  # the estimate is the arm's time: its durations are the model's
            ends, pace = [sent.est_end_s for sent in self.pending], 1.0
        else:
            pace = self.pace
        # The lead in the arm's seconds: ``ends`` are the arm's, each duration × the pace (the model
        # seconds of ``lead_model_s``, the same thing measured the other way)
        tail_s, lead_s, duration_s = ends[-1], self.lead_model_s * pace, duration_s * pace
        lead_ok_at = tail_s - min(lead_s, FEED_AHEAD_S / self.pace * pace)  # the arm must not run dry
        if duration_s <= lead_s:
            # The waiting motion once frame j is in progress is tail − end of j: find the first
            # frame after which the new one fits within the lead; it may go once that one began.
            threshold_s = tail_s + duration_s - lead_s
            began_s = None
            for end_s in ends:
                if end_s >= threshold_s:
                    break
                began_s = end_s
            if began_s is None:
                # the new one fits behind every frame after the first once the first has begun —
                # not before: a frame written ahead (``write_ahead_s``) while the first is still on
                # the wire would leave the whole queue to run after a stop then
                began_s = max(now, ends[0] - self.pending[0].segment.duration_s * pace)
            lead_ok_at = min(lead_ok_at, began_s)
        when = max(now, wire_ok_at, lead_ok_at)
        if when <= now:
            self.write_reason = WaitReason.READY
        else:
            # a tie is the wire's: the frame before must leave it first whatever the lead says (a frame
            # written ahead waits for the one before to begin, which is when the line frees in virtual time)
            self.write_reason = WaitReason.LEAD if lead_ok_at > wire_ok_at + 1e-9 else WaitReason.WIRE
        return when

    def _arm_ends(self) -> list[float] | None:
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
        pin, pace = self._pin, self.pace
        if pin is None or pace < PACE_FOLLOWED:
            return None
        at_s, index, left_s = pin
        end_s = at_s + left_s * pace  # the pinned frame's end
        ends = []
        for sent in self.pending:
            if sent.index < index:
                ends.append(sent.est_end_s)
                continue
            if sent.index > index:
                end_s = max(sent.wire_end_s, end_s) + sent.segment.duration_s * pace
            ends.append(end_s)
        return ends

    @property
    def lead_model_s(self) -> float:
        """The lead in model seconds: the arm runs ``pace`` times slower than the model."""
        return self.lead_s / self.pace

    def worktable_xyz(self, xyz) -> tuple[float, float, float]:
        """A reported X/Y/Z in the worktable frame of the last frame written (the frame the job
        plans in): robot coordinates less the origin when the arm reports those (status_xyz_frame)."""
        return _in_frame(tuple(xyz), self.planner.pose.origin_mm) if self.reports_robot_xyz else tuple(xyz)

    def may_write(self, now: float, command: Command | None = None) -> bool:
        when = self.next_write_time(now, command)
        return when is not None and when <= now

    def _plan(self, command: Command) -> Segment:
        """The segment ``command`` would make if written next (kept for ``wrote``)."""
        if self._peeked is None or self._peeked[0] is not command:
            planner = self.planner
            self._peeked = (command, planner.model.plan(command, planner.pose, planner.pending_arc))
        return self._peeked[1]

    def line_busy_until(self, until_s: float) -> None:
        """The port says bytes written before are still leaving until ``until_s`` (its
        ``out_waiting``): the next frame starts no earlier (landing times from what has left)."""
        if until_s > self.wire_free_s:
            self.wire_free_s = until_s

    def wrote(self, command: Command, now: float, tag: object = None) -> SentFrame:
        """Record that the next frame's first byte went on the wire at ``now``."""
        segment = self._plan(command)
        self._peeked = None
        planner = self.planner
        e_unknown = self._moves_e_from_the_start(command, segment)
        allowance_s = math.inf if e_unknown else self._unknown_start_s(segment)
        sure_s = 0.0 if allowance_s else segment.duration_s  # (every path_known False frame has an allowance)
        planner.pending_arc = command if isinstance(command, ArcStart) else None
        planner.pose = segment.end
        start_s = max(now, self.wire_free_s)
        wire_end = start_s + self.frame_s
        self.wire_free_s = wire_end
        previous = self.pending[-1] if self.pending else None
        est_start = max(wire_end, previous.est_end_s if previous else wire_end)
        if previous is None:
            self._pin = (est_start, self.sent, segment.duration_s)  # the arm waits for it: it starts on the arm's time
        certain_start = max(wire_end + ARRIVAL_SLACK_S, self._certain_tail_s)
        self._certain_tail_s = (certain_start + (segment.duration_s + allowance_s) * self.slowest_factor
                                + self.frame_slack_s)
        frame = SentFrame(
            index=self.sent, command=command, segment=segment, tag=tag, wire_end_s=wire_end,
            est_end_s=est_start + segment.duration_s, certain_end_s=self._certain_tail_s,
            chain_end_s=self._certain_tail_s, group_index=self.sent, motion_before_s=self.motion_sent_s,
            unknown_start_s=allowance_s, sure_before_s=self.sure_motion_sent_s, sure_s=sure_s,
            timing_known=not e_unknown,
            path_known=not (self.sent > 0 and self._start_unknown(segment)),
        )
        self.motion_sent_s += segment.duration_s
        self.sure_motion_sent_s += frame.sure_s
        if isinstance(command, ResetConnector):  # it clears what is queued when it acts
            self._reset_index = frame.index
            if self.control_on_arrival:
                for sent in self.pending:
                    sent.may_be_cleared = True
        elif (not self.control_on_arrival and self._reset_index is not None and self.pending
              and self.pending[0].index <= self._reset_index):
            frame.may_be_cleared = True  # queued behind a RESET CONNECTOR (H5) that may not have acted yet
        self._recent_sent.append(frame)
        if isinstance(command, ArcStart):
            # The arm holds a G300 at the head until its G301 has landed and runs both as one
            # segment: the G300 finishes only with the arc, whenever its G301 is written.
            frame.certain_end_s = float("inf")
        elif previous is not None and isinstance(previous.command, ArcStart) and previous.index == self.sent - 1:
            if isinstance(command, ArcEnd):
                frame.group_index = previous.index
                previous.certain_end_s = frame.certain_end_s
            else:
                previous.certain_end_s = previous.chain_end_s  # the arm skips a G300 left alone
        if segment.kind == "joint" and self.kinematics_verified:
            frame.xyz_tolerance_mm = POSITION_TOLERANCE_MM + JOINT_TRACE_SLACK * _trace_deviation_mm(segment)
        self.pending.append(frame)
        if segment.kind in ("line", "arc"):
            self._cartesian.append(frame.index)
        elif not frame.path_known:
            self._joints_unknown.append(frame.index)
        if self._xyz_unknown(segment) or not frame.path_known:
            self._blind.append(frame.index)
        self.sent += 1
        return frame

    # --- reading ----------------------------------------------------------------------------

    def receive_status(self, frame: StatusFrame, now: float) -> None:
        """Take one status frame read at ``now``."""
        self.status_frames += 1
        kind = frame.KIND  # (every status frame: one test a kind, the rest only counted)
        if kind == _POSITION_KIND:
            self._observe((frame.x_mm, frame.y_mm, frame.z_mm), now)
        elif kind == _JOINTS_LOW_KIND:
            self._observe_joint_half(0, (frame.j1_deg, frame.j2_deg, frame.j3_deg), now)
        elif kind == _JOINTS_HIGH_KIND:
            self._observe_joint_half(3, (frame.j4_deg, frame.j5_deg, frame.j6_deg), now)
        elif kind == _PAUSE_KIND:
            self._note_pause_state(frame.paused, now)
        pending, running_s = self.pending, self._running_seen_s
        if pending and running_s is not None and pending[0].certain_end_s <= running_s:
            self._advance_by_time()  # (its first tests inline: every status frame)

    def _note_pause_state(self, paused: bool, now: float) -> None:
        if paused:
            self._pin = None  # the arm held still: where it was pinned no longer says where it is
            self._pace_from.clear()  # a pace sample must not span a pause (arrival mode freezes a move)
            self._span_from.clear()
            self._span_last.clear()
        if paused and not self._paused and self._running_seen_s is not None:
            self._pause_began_s = self._running_seen_s  # it may have begun right after
        if not paused:
            if self._paused:
                # Everything still pending waited at least from the last sighting of a running
                # arm to now: push the certain end times back by that much.
                shift = now - self._pause_began_s
                for sent in self.pending:
                    sent.certain_end_s += shift
                    sent.chain_end_s += shift
                self._certain_tail_s += shift
            self._running_seen_s = now
        self._paused = paused

    def cleared(self) -> None:
        """The connector may have discarded the frames still queued (a RESET CONNECTOR that acts
        as it lands): the time bound assumes every frame written waits in the FIFO, so from now
        on only the arm's reports confirm a pending frame."""
        self._time_proves = False
        for sent in self.pending:
            sent.may_be_cleared = True

    def _advance_by_time(self) -> None:
        if self._running_seen_s is None or self._paused or not self._time_proves:
            return
        certain_now = self._running_seen_s
        # (a frame a RESET CONNECTOR may have cleared has no time to finish in: reports decide it)
        while self.pending and self.pending[0].certain_end_s <= certain_now and not self.pending[0].may_be_cleared:
            self._consume_one(by_reports=False)
            self.bound_evidence = Evidence.TIME

    def _consume_before(self, index: int) -> None:
        """Every frame before ``index`` is known finished — except the rest of its group (a G300
        finishes with its G301, so evidence of the arc proves nothing about the G300)."""
        if self.pending:
            k = index - self.pending[0].index
            if 0 < k < len(self.pending):
                index = self.pending[k].group_index
        while self.pending and self.pending[0].index < index:
            self._consume_one(by_reports=True)

    def _restart_time_bound(self, index: int, now: float, fraction: float = 0.0) -> None:
        """Frame ``index`` has begun by ``now`` and its arm is at least ``fraction`` along its path
        (agreed evidence): restart the time bound's chain there, since a chain that began at the
        first frame of a long job drifts ahead by the slowest-arm factor for as long as the arm
        is kept busy."""
        if not self.pending:
            return
        chain = None
        for k in range(index - self.pending[0].index, len(self.pending)):
            if k < 0:
                return  # that frame is already known finished: nothing about the next ones
            sent = self.pending[k]
            if chain is None:  # the rest of it, from the least fraction the evidence allows
                left_s = sent.segment.duration_s - _time_window(sent.segment, fraction, 1.0, self._time_at)[0]
                chain = now + (left_s + sent.unknown_start_s) * self.slowest_factor + self.frame_slack_s
            else:
                start = max(sent.wire_end_s + ARRIVAL_SLACK_S, chain)
                chain = start + (sent.segment.duration_s + sent.unknown_start_s) * self.slowest_factor + self.frame_slack_s
            if chain >= sent.chain_end_s:
                return  # no tighter than before, and neither are the frames after it
            sent.chain_end_s = chain
            if not isinstance(sent.command, ArcStart):
                sent.certain_end_s = chain
                if sent.group_index != sent.index and k > 0:
                    self.pending[k - 1].certain_end_s = chain  # its G300 finishes with it
            elif k + 1 < len(self.pending) and self.pending[k + 1].group_index != sent.index:
                sent.certain_end_s = chain  # a G300 not followed by its G301: skipped
        self._certain_tail_s = chain

    def _xyz_unknown(self, segment: Segment) -> bool:
        """Whether the segment's X/Y/Z exist only through the profile's unverified kinematics (a
        joint move, or a still frame whose pose was derived): no sighting can judge it."""
        return not self.kinematics_verified and (segment.kind == "joint" or segment.end.xyz_derived)

    def _start_unknown(self, segment: Segment) -> bool:
        """Whether a segment starts where only the profile's unverified kinematics say — a
        Cartesian one at a joint move's end, a joint one at a Cartesian move's end: its real path
        is not the planned one."""
        if self.kinematics_verified:
            return False
        if segment.kind == "joint":
            return segment.start.joints_derived
        return segment.kind in ("line", "arc") and segment.start.xyz_derived

    def _unknown_start_s(self, segment: Segment) -> float:
        """The time bound's allowance for a Cartesian move that starts where only the profile's
        kinematics say (the end of a joint move): with kinematics not verified on this arm, its
        true start may lie ``UNVERIFIED_FK_SHARE`` of the reach away, so the move may be that much
        longer than planned — covered at its own feed (half of it for a move that ramps from rest),
        held to the profile's speed limit as the plan holds it, in the model's seconds (its
        speed_factor: the durations it is added to are).  For a line that bounds it (a start r
        away makes it at most r longer).  For an arc nothing does: the circle through a start r
        away, the G300 point and the end grows without bound as that start nears the G300 point
        (tests/test_unverified_joint_end.py found a 571 mm arc overrun), so time never
        confirms it — a sighting on a later frame does, or the arm at rest at the last target
        (``confirm_all_done``, which armctl/job.py also applies while the FIFO bound holds the job).
        And the other way round: a joint move from the end of a Cartesian one starts at joints only
        the arm's own IK knows, anywhere within the joint limits (``joint_move_from_anywhere_s``);
        its end is exact, so its sightings hold (found: an arm 2x slower, links 5 % short, the
        probe's speed_tolerance 1.05 — a joint move the plan made 0 s long claimed done by time)."""
        if not self._start_unknown(segment):
            return 0.0
        if segment.kind == "joint":  # (and a fixed pose) from the end of a Cartesian move
            return 0.0 if self.sent == 0 else self.planner.model.joint_move_from_anywhere_s(segment)
        if segment.kind == "arc" or isinstance(segment.command, ArcEnd):  # (planned as a line when its
            return math.inf  # points coincide or line up: through the real start they need not)
        command, model = segment.command, self.planner.model
        speed_mm_min = getattr(command, "speed_mm_min", None) or getattr(command, "speed1_mm_min", 0.0) / 2
        speed_mm_min = min(speed_mm_min, model.profile.speed.max_linear_mm_min)
        return self._unknown_start_mm / max(speed_mm_min / 60.0, 1e-3) * model.speed_factor

    def _moves_e_from_the_start(self, command: Command, segment: Segment) -> bool:
        """Whether this is the first move that sets E0/E1 (every move carries them) and moves them
        as planned.  No status kind reports them, so where they start is unknown — the reported
        start pose takes the profile's 0, the arm's state at power-on — and that move may need
        any time for them: none (an arm whose axes stand at its targets already: a 2.6 s move of
        U240 planned, none run, and the job 'finished early'), or more than planned (from farther
        away: the arm then looks slower than the model).  So its time is not known
        (``SentFrame.timing_known``), the loss checks count none of it, and time never confirms it
        (as an arc from an unknown start): a later frame's sighting does, or the arm at rest."""
        if self._e_known or segment.kind == "still" or not hasattr(command, "e0_deg"):
            return False
        self._e_known = True
        start = segment.start
        return (start.e0_deg, start.e1_deg) != (command.e0_deg, command.e1_deg)

    def _consume_one(self, by_reports: bool, at_rest: bool = False) -> None:
        """Count the oldest pending frame consumed: by the arm's reports, or by time — the time
        bound's, or (``at_rest``) the caller's, the trailing frames' at the end of a job (which
        leaves the time bound's own record, ``first_time_only_index``, as it was)."""
        sent = self.pending.popleft()
        self._last_done_tag = sent.tag
        self.consumed_lower_bound += 1
        if by_reports:
            # A report on a later frame (or the arm at rest at the end) proves a frame left the
            # FIFO; that the arm ran it only if the FIFO held it (no drop, no RESET CONNECTOR),
            # or the arm at rest at its very target says so.
            if sent.seen or self.fifo_holds_all and not sent.may_be_cleared:
                self.confirmed_by_reports += 1
            else:
                self.confirmed_unseen += 1
        elif at_rest:
            self.confirmed_by_time += 1
        else:
            if self.confirmed_by_time == 0:
                self.first_time_only_index = self.consumed_lower_bound - 1
                self._least_factor_confirmed = self.slowest_factor
            self.confirmed_by_time += 1

    def _observe(self, xyz, now: float) -> None:
        robot, xyz_unknown = self.reports_robot_xyz, self._xyz_unknown

        def match(sent: SentFrame):
            segment = sent.segment
            if xyz_unknown(segment):
                return None  # its X/Y/Z exist only through the profile's unverified FK
            distance, fraction = distance_to_path(segment, _in_frame(xyz, segment.start.origin_mm) if robot else xyz)
            if distance > sent.xyz_tolerance_mm:
                return None
            if segment.kind == "joint":
                slack = JOINT_TRACE_FRACTION  # matched on chords of its trace
            else:
                slack = sent.xyz_tolerance_mm / segment.length if segment.length > 0 else 1.0
            if not sent.path_known:
                # on the planned path near where the real one may run: at least this far along,
                # perhaps past its end already (the search stops at it), so no upper end —
                # else the arm at rest at its target would hold the estimate there for ever
                return fraction - slack, math.inf
            return fraction - slack, fraction + slack

        # A position says nothing about a frame whose X/Y/Z only the unverified kinematics know,
        # nor about any frame after it: the arm may be on that frame, at a point that also lies
        # on a later path (a wrist turning in place, then a move that starts there).
        blind, first = self._blind, self.pending[0].index if self.pending else self.sent
        while blind and blind[0] < first:
            blind.popleft()  # consumed
        end = blind[0] - first if blind else len(self.pending)
        if blind and not self.pending[end].path_known:
            end += 1  # a line from an unverified joint end: a sighting may count on it, never past it
        if blind and end == 0:
            return
        def could_be_on(sent: SentFrame) -> bool:  # for the loss check: a frame this report may lie on
            segment = sent.segment
            return xyz_unknown(segment) or not sent.path_known or match(sent) is not None

        earliest, candidates, settled = self._search(match, end, now)
        if earliest is None and end < len(self.pending):
            # the arm may be on the frame that cannot be judged: no evidence — but a report on
            # a later frame's path still tells the estimate where the arm most likely is
            self._reanchor_beyond(match, end, now)
            return
        self._check_reversal(xyz if earliest is None and not blind else None, match)
        self._use("position", earliest, candidates, now, could_be_on, settled)

    def _check_reversal(self, xyz, match) -> None:
        """A sign of loss: the arm reported, twice in a row, on the inside of the path of a frame
        already known finished (the lower bound never passes the truth) and on no pending path —
        it went back over its job, which an arm running its frames in order never does.  ``xyz``
        is None when the report lies on a pending path (or one that cannot be judged).  Only
        straight and arc moves with a start the arm reported count, away from their ends (where
        the next frame begins); two reports on the same finished frame, not one, so a corrupted
        frame never raises it."""
        previous, self._reversed_on = self._reversed_on, None
        if xyz is None or not self.pending:
            return
        first = self.pending[0].index
        for sent in self._recent_sent:
            if sent.index >= first:
                break
            segment = sent.segment
            if segment.kind not in ("line", "arc") or segment.length <= 4 * sent.xyz_tolerance_mm:
                continue
            if self._start_unknown(segment):
                continue  # its path starts where only the profile's kinematics say
            found = match(sent)
            if found is None or found[0] <= 0.0 or found[1] >= 1.0:
                continue
            self._reversed_on = sent.index
            if previous != sent.index:
                return
            self.losses.append(f"the arm was seen back on {_where(sent)}, a frame already finished, twice in a row "
                               "and on no frame still to run: it did not run the job in order")
            if self.first_suspect_index is None or first < self.first_suspect_index:
                self.first_suspect_index = first
            return

    def _observe_joint_half(self, offset: int, values, now: float) -> None:
        """Joint halves say nothing about a Cartesian segment (that would need IK), so a match
        on a joint segment counts only up to the first pending Cartesian segment."""
        if not self.pending:
            self._use(f"joints{offset}", None, [], now)
            return
        cartesian, first = self._cartesian, self.pending[0].index
        while cartesian and cartesian[0] < first:
            cartesian.popleft()  # consumed
        end = cartesian[0] - first if cartesian else len(self.pending)
        if end == 0:
            return  # the arm may be on this Cartesian segment: no evidence from joints
        unknown = self._joints_unknown
        while unknown and unknown[0] < first:
            unknown.popleft()  # consumed
        if unknown and unknown[0] - first < end:
            # A joint move from a Cartesian end (its real start only the arm's IK knows): its
            # real path may pass along a later frame's, so a sighting counts on it, never past it.
            end = unknown[0] - first + 1
        verified = self.kinematics_verified

        def match(sent: SentFrame):
            if not verified and sent.segment.end.joints_derived:
                return None  # a still frame whose joints exist only through the profile's unverified IK
            found = _joint_half_fraction(sent.segment, offset, values)
            if found is None or sent.path_known:
                return found
            return found[0], math.inf  # at least this far along, perhaps past its end already

        def could_be_on(sent: SentFrame) -> bool:  # for the loss check: joints cannot judge a Cartesian frame
            return sent.segment.kind not in ("joint", "still") or match(sent) is not None

        earliest, candidates, settled = self._search(match, end, now)
        if earliest is None and end < len(self.pending):
            return  # the arm may be on the Cartesian segment after these: no evidence
        self._use(f"joints{offset}", earliest, candidates, now, could_be_on, settled)

    def _scan(self, match, end: int, now: float):
        """``_search``'s (earliest, candidates)."""
        return self._search(match, end, now)[:2]

    def _search(self, match, end: int, now: float):
        """Match one observation against the pending frames before ``end``: (earliest, candidates,
        settled) — settled when the earliest candidate is the one where the estimate has the arm
        (nothing to re-anchor: ``_use``).

        Flat cost: the search covers the oldest ``SCAN_WINDOW_FRAMES`` pending frames (where the
        lower bound's evidence is) and as many around the frame the estimate has in progress
        (where the re-anchoring evidence is); the rest only when neither window matches.  The
        earliest candidate stays sound: with no match among the oldest frames and a match
        further on, the arm is at least at the first frame not searched, so that is the
        earliest index reported (evidence no stronger than what was searched)."""
        pending = self.pending
        if 0 < end < len(pending):
            # Cut before a frame this stream cannot judge: seen at the end of the last frame it
            # can (or anywhere on a still one), the arm may be past it already, so that window has
            # no upper end — else an arm at rest there (a held G300 whose joints 4-6 the arc
            # keeps, the target of a joint move) would hold the estimate, and the job's end, back.
            edge, judge = pending[end - 1], match

            def match(sent: SentFrame):
                found = judge(sent)
                if sent is edge and found is not None and found[1] >= 1.0:
                    return found[0], math.inf
                return found
        candidates: list[tuple[int, float, float]] = []
        head = min(end, SCAN_WINDOW_FRAMES)
        for k in range(head):
            sent = pending[k]
            found = match(sent)
            if found is not None:
                candidates.append((sent.index, *found))
                if _estimate_off_s(sent, *found, now, self._time_at) == 0.0:
                    # The usual case: the earliest candidate is where the estimate has the arm,
                    # so no later candidate can change the bound or the estimate.
                    return sent.index, candidates, True
                break
        else:
            k = head

        def search(lo: int, hi: int) -> None:
            for j in range(lo, hi):
                sent = pending[j]
                found = match(sent)
                if found is not None:
                    candidates.append((sent.index, *found))

        search(k + 1, head)
        if head == end:
            return (candidates[0][0] if candidates else None), candidates, False
        in_head = bool(candidates)
        centre = bisect_right(pending, now, key=_est_end)  # the frame the estimate has in progress
        lo = max(head, centre - SCAN_WINDOW_FRAMES // 2)
        hi = min(end, max(lo, centre + SCAN_WINDOW_FRAMES // 2))
        search(lo, hi)
        if in_head or (candidates and lo == head):
            return candidates[0][0], candidates, False
        if candidates:
            # Nothing among the oldest frames: the arm is at least at the first frame not searched.
            return pending[head].index, candidates, False
        search(head, lo)  # neither window matched (the estimate is far off, or this is noise)
        search(hi, end)
        return (candidates[0][0] if candidates else None), candidates, False

    def _use(self, stream: str, earliest: int | None, candidates: list[tuple[int, float, float]],
             now: float, could_be_on=None, settled: bool = False) -> None:
        """Move the lower bound and the estimate on one observation's candidate segments.

        ``earliest`` is where the arm is at least; the bound moves there only when the previous
        observation of the same stream agrees, so one corrupted frame cannot.  ``could_be_on``
        (a frame → whether this report may have been taken on it) serves the loss check;
        ``settled`` (``_scan``): the estimate already has the arm where the earliest candidate
        does — nothing below moves it, so re-anchoring would find nothing to do.
        """
        previous = self._last_candidate.get(stream)
        previous_fraction = self._last_fraction.get(stream)
        self._last_candidate[stream] = earliest
        fraction = None
        for index, lo, _ in candidates:
            if index == earliest:
                fraction = lo
                break
        self._last_fraction[stream] = fraction
        if earliest is None:
            return
        if previous is not None:
            agreed = min(previous, earliest)
            if could_be_on is not None:
                # a gap found is told once: the next one is judged from here
                if self._check_gap(stream, agreed, now, could_be_on) or previous == earliest:
                    self._sighting[stream] = (earliest, now, could_be_on)
            before = self.consumed_lower_bound
            self._consume_before(agreed)
            if self.consumed_lower_bound > before:
                self.bound_evidence = Evidence.POSITION if stream == "position" else Evidence.JOINTS
            both = (previous == earliest and fraction is not None and previous_fraction is not None)
            self._restart_time_bound(agreed, now, max(0.0, min(previous_fraction, fraction)) if both else 0.0)
            if agreed == earliest:
                self._measure_pace(stream, earliest, candidates, now, could_be_on)
        if not settled:
            self._reanchor(candidates, now)
        if self.pace >= PACE_FOLLOWED:
            self._pin_estimate(candidates, now)

    def _pin_estimate(self, candidates: list[tuple[int, float, float]], now: float) -> None:
        """``_pin`` where this sighting pins the estimate: the estimate has the arm in the window of
        a candidate inside a path that moves (a short window).  One on a still frame (a delay, a
        PWM change) or at a path's end only bounds it: the arm may rest there in frames the
        estimate ran through already, an arm slower than the model still in the first."""
        pending = self.pending
        if not pending:
            return
        first = pending[0].index
        for index, lo, hi in candidates:
            k = index - first
            if 0 <= k < len(pending) and _estimate_off_s(pending[k], lo, hi, now, self._time_at) == 0.0:
                sent = pending[k]
                if sent.segment.length > 0 and lo > 0.0 and hi < 1.0:
                    self._pin = (now, sent.index, max(0.0, sent.est_end_s - now))
                return

    def _check_gap(self, stream: str, index: int, now: float, could_be_on) -> bool:
        """A sign of loss: the arm, seen by this stream at ``now`` at least at frame ``index``,
        got there from its last agreed sighting sooner than the frames in between could take at
        the fastest plausible pace (``fastest_factor``): they were skipped — dropped by a full
        FIFO or cleared.  Sound on a good arm: lost status frames only lengthen the interval, and
        the earlier sighting counts at the latest frame its report may lie on (a repeated path,
        a frame this stream cannot judge) that is no later than the latest frame this report
        (``could_be_on``) may lie on — the arm runs its frames in order — so a return to the
        same place is no gap."""
        last = self._sighting.get(stream)
        recent = self._recent_sent
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
            f"the arm got from {_where(upper)} to {_where(at_k)} in {now - since:.2f} s, but the "
            f"{skipped} frame{'s' if skipped != 1 else ''} between take {gap_s:.2f} s of motion "
            f"(at least {gap_s * self.fastest_factor:.2f} s on an arm {1 / self.fastest_factor:g}x faster than the "
            "model): they were skipped (dropped by a full FIFO, or cleared)")
        suspect = last[0]  # the arm may have been on a later frame through the same point: not claimed
        if self.first_suspect_index is None or suspect < self.first_suspect_index:
            self.first_suspect_index = suspect
        return True

    def tag_of(self, index: int):
        """The tag of frame ``index`` if it is among the frames kept, else None."""
        recent = self._recent_sent
        if not recent or not recent[0].index <= index <= recent[-1].index:
            return None
        return recent[index - recent[0].index].tag

    def _measure_pace(self, stream: str, index: int, candidates, now: float, could_be_on=None) -> None:
        """One more pace sample when this stream saw the arm on frame ``index`` before, at least
        ``PACE_MIN_SPAN_S`` of model time earlier along its path (two sightings on one segment:
        the arm ran between them, neither waiting for the line nor between frames)."""
        if not self.pending or index < self.pending[0].index:
            return
        found = None
        for k, lo, hi in candidates:
            if k == index:
                found = (lo, hi)
                break
        sent = self.pending[index - self.pending[0].index]
        if not sent.timing_known:
            return  # its time may be any: no pace, no slowness from it
        segment = sent.segment
        if found is None or segment.length <= 0 and segment.kind != "joint":
            self._pace_from.pop(stream, None)
            return
        lo, hi = found
        if lo <= 0.0 or hi >= 1.0:
            return  # a window cut at an end of the path: its middle is not where the arm was
        model_s = segment.time_at_fraction((lo + hi) / 2)
        if could_be_on is not None:
            self._check_slowness(stream, index, segment, lo, hi, now, could_be_on)
        last = self._pace_from.get(stream)
        if last is None or last[0] != index or model_s < last[1]:
            self._pace_from[stream] = (index, model_s, now)
            return
        if model_s - last[1] < PACE_MIN_SPAN_S:
            return
        self._pace_samples.append((now - last[2]) / (model_s - last[1]))
        self._pace_from[stream] = (index, model_s, now)
        pace, self.pace = self.pace, min(PACE_MAX, max(1.0, *self._pace_samples))
        if self.pace != pace:
            self.plan_changes += 1
        # An arm measured slower than its profile's speed_factor: the time bound allows that much
        # more from here on (only ever more careful; whatever it confirmed before is judged by
        # ``_check_slowness``).
        wider = self._tolerance * self.pace
        if wider > self.slowest_factor:
            self._widen_time_bound(wider)

    def _widen_time_bound(self, factor: float) -> None:
        """From now on the time bound allows an arm ``factor`` times slower than the model; the
        pending frames' deadlines move back by what the wider factor adds to each of them and to
        every pending frame before it (a chain can only end later, never earlier)."""
        extra = factor - self.slowest_factor
        self.slowest_factor = factor
        added_s = 0.0
        for sent in self.pending:
            added_s += (sent.segment.duration_s + sent.unknown_start_s) * extra
            sent.chain_end_s += added_s
            sent.certain_end_s += added_s  # inf (a G300 waiting for its G301) stays inf
        self._certain_tail_s += added_s

    def _check_slowness(self, stream: str, index: int, segment: Segment, lo: float, hi: float, now: float,
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
        t_lo, t_hi = self._time_at(segment, lo), self._time_at(segment, hi)
        last = self._span_last.get(stream)
        self._span_last[stream] = (index, t_lo, t_hi, now)
        if last is None or last[0] != index:
            self._span_from.pop(stream, None)
            return
        first = self._span_from.get(stream)
        if first is None or first[0] != index:
            self._span_from[stream] = (index, min(last[1], t_lo), now)  # at least there, at b's time
            return
        model_span_s = max(last[2], t_hi) - first[1]  # at most there, at a's time
        arm_span_s = last[3] - first[2] - 2 * STATUS_PERIOD_S
        if model_span_s <= 0 or arm_span_s <= 0:
            return
        slowest = arm_span_s / model_span_s
        if slowest <= self._tolerance or (self._too_slow is not None and slowest <= self._too_slow[0]):
            return
        k = index - self.pending[0].index
        if any(could_be_on(self.pending[j]) for j in range(k + 1, len(self.pending))):
            return  # the arm may be on a later frame through the same point: no judgement
        self._too_slow = (slowest, self.pending[k])
        self.slowest_proven = max(self.slowest_proven, slowest)

    def _time_at(self, segment: Segment, fraction: float) -> float:
        """``segment.time_at_fraction(fraction)``, remembered for the segment last asked about:
        one sighting asks for its window's ends up to four times each (the scan, the
        re-anchoring, the slowness check, the time bound's restart — from the previous
        sighting's least fraction, too), 4,461 sightings in a 20-minute job."""
        if segment is not self._times_segment:
            self._times_segment, self._times = segment, {}
        times = self._times
        t_s = times.get(fraction)
        if t_s is None:
            if len(times) >= 32:
                times.clear()
            t_s = times[fraction] = segment.time_at_fraction(fraction)
        return t_s

    def _reanchor_beyond(self, match, end: int, now: float) -> None:
        """The estimate (never the lower bound) re-anchored on a report that lies on the path of
        a pending frame at or after ``end``, past a frame the stream cannot judge (a move from a
        joint end the profile's kinematics do not verify, whose real length and path only the
        arm knows).  Without it the estimate runs on by the plan while the arm is still on that
        frame, so the lead counts less motion queued than there is and an abort outruns the stop
        bound (``armctl bench``'s ``kinematics`` row: 3.50 s moved against 2.88 s).  A report
        on one of those paths is evidence for the estimate only: it may also lie on the frame
        that cannot be judged, so nothing is proven by it.  Flat cost: the frames searched are
        a window around the frame the estimate has in progress."""
        pending = self.pending
        current = next((k for k in range(end, len(pending)) if pending[k].est_end_s > now), len(pending) - 1)
        lo_k, hi_k = max(end, current - SCAN_WINDOW_FRAMES), min(len(pending), current + SCAN_WINDOW_FRAMES)
        candidates = []
        for k in range(lo_k, hi_k):
            found = match(pending[k])
            if found is not None:
                candidates.append((pending[k].index, *found))
        if candidates:
            self._reanchor(candidates, now)

    def _reanchor(self, candidates: list[tuple[int, float, float]], now: float) -> None:
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
        if not self.pending:
            return
        first = self.pending[0].index
        best = None
        for index, lo, hi in candidates:
            if index < first:
                continue
            off = _estimate_off_s(self.pending[index - first], lo, hi, now, self._time_at)
            if best is None or off < best[0]:
                best = (off, index - first, lo, hi)
            if off == 0.0:
                break
        if best is None or best[0] == 0.0:
            return
        _, k, lo, hi = best
        self.plan_changes += 1
        sent = self.pending[k]
        t_lo, t_hi = _time_window(sent.segment, lo, hi, self._time_at)
        start = sent.est_end_s - sent.segment.duration_s
        start = now - t_lo if now < start + t_lo else now - t_hi
        sent.est_end_s = start + sent.segment.duration_s
        if sent.group_index != sent.index and k > 0:
            self.pending[k - 1].est_end_s = start  # its G300: the arc's start
        previous_end_s = sent.est_end_s
        for j in range(k + 1, len(self.pending)):
            nxt = self.pending[j]
            end_s = max(nxt.wire_end_s, previous_end_s) + nxt.segment.duration_s
            if end_s == nxt.est_end_s:
                break  # and so are the frames after it
            nxt.est_end_s = previous_end_s = end_s

    # --- the end of a job ---------------------------------------------------------------------

    def estimated_finish_s(self) -> float | None:
        return self.pending[-1].est_end_s if self.pending else None

    @property
    def all_consumed(self) -> bool:
        """Every frame written is known to have finished."""
        return not self.pending

    def confirm_all_done(self, now: float | None = None, before: int | None = None) -> None:
        """The caller saw the arm at rest at the last frame's target: every frame written has
        run — except a trailing G300, which the arm holds until its G301 comes.  Sound only on
        the caller's proof (armctl/job.py): every status kind re-read unchanged, and no frame
        that moves nothing (where the arm rests too) left before the last motion unproven.
        With ``now`` (the proof taken mid-job, more to be written) the time bound's chain starts
        again there: it may have run to infinity behind an arc it cannot bound.  With ``before``
        (mid-job too: the arm rests in that frame or later) only the frames before it."""
        pending = self.pending
        if pending and (before is None or pending[-1].index < before) and self.ran_at_rest(pending[-1]):
            pending[-1].seen = True
            if pending[-1].group_index != pending[-1].index and len(pending) > 1:
                pending[-2].seen = True  # its G300
        while pending and (before is None or pending[0].index < before) and not (
                len(pending) == 1 and isinstance(pending[0].command, ArcStart)):
            # a frame that leaves no trace (unless seen): the caller's proof of it is time
            self._consume_one(by_reports=pending[0].seen or pending[0].segment.moves_reported, at_rest=True)
            self.bound_evidence = Evidence.AT_REST
        if now is None:
            return
        if pending:
            self._restart_time_bound(pending[0].index, now)  # the held G300 is at the head
        else:
            self._certain_tail_s = min(self._certain_tail_s, now)

    def ran_at_rest(self, last: SentFrame) -> bool:
        """Whether the arm at rest at the target of ``last`` (a frame written; the caller saw it
        there) proves it ran — had it been dropped or cleared, the arm would rest where an
        earlier frame ended — that is, unless that is where the arm may rest anyway: at its
        start, or at the end of an earlier frame kept (a way back to the same point), or
        somewhere only the profile's kinematics know (its path not the planned one)."""
        segment = last.segment
        if not (segment.moves_reported and last.path_known):
            return False
        by_joints = segment.kind == "joint" or segment.end.xyz_derived  # what ``Job._at_end_of`` compares
        tolerance = 2 * (JOINT_TOLERANCE_DEG if by_joints else POSITION_TOLERANCE_MM)
        target = segment.end.joints if by_joints else segment.end.xyz
        for sent in self._recent_sent:  # (``last`` among them: its own start, then no further)
            pose = segment.start if sent is last else sent.segment.end
            if pose.origin_mm != segment.end.origin_mm:
                return False
            derived = pose.joints_derived if by_joints else pose.xyz_derived  # the profile's IK/FK: where?
            if derived and not self.kinematics_verified:
                return False
            if max(abs(a - b) for a, b in zip(pose.joints if by_joints else pose.xyz, target)) <= tolerance:
                return False
            if sent is last:
                return True
        return False

    def check_time_bound(self) -> None:
        """A sign of loss, told at the end of a job: the arm was proven to run a frame slower than
        the profile's ``speed_tolerance`` (``_check_slowness``) and slower than the factor the
        time bound used when it first confirmed a frame (before a measured pace widened it), so
        what time confirmed may not have run when more frames were written (dropped by a full
        FIFO).  Said only when time confirmed a frame and was still trusted (not ``cleared``)."""
        least = self._least_factor_confirmed
        if self._too_slow is None or least is None or self._too_slow[0] <= least or not self._time_proves:
            return
        slowest, sent = self._too_slow
        self._too_slow = None
        self.losses.append(
            f"the arm ran {_where(sent)} at least {slowest:.2f}x slower than the model, but the time bound allowed "
            f"{least:g}x (the profile's [connector] speed_tolerance) when it confirmed frames: they may not have run "
            "when more were written (dropped by a full FIFO?); run `armctl probe` again")
        suspect = self.first_time_only_index or 0
        if self.first_suspect_index is None or suspect < self.first_suspect_index:
            self.first_suspect_index = suspect

    def last_known_done(self):
        """The tag of the last frame known finished, or None."""
        return self._last_done_tag


_POSITION_KIND, _JOINTS_LOW_KIND, _JOINTS_HIGH_KIND, _PAUSE_KIND = (
    PositionStatus.KIND, JointsLowStatus.KIND, JointsHighStatus.KIND, PauseStatus.KIND)


def _where(sent: SentFrame) -> str:
    """A frame as the user knows it: its script line when the tag has one."""
    line = getattr(sent.tag, "line", None)
    return f"frame {sent.index + 1}" if line is None else f"frame {sent.index + 1} (line {line})"


def _in_frame(xyz, origin_mm) -> tuple[float, float, float]:
    """Robot X/Y/Z in the worktable frame whose origin (in robot coordinates) is ``origin_mm``."""
    return (xyz[0] - origin_mm[0], xyz[1] - origin_mm[1], xyz[2] - origin_mm[2])


def _est_end(sent: SentFrame) -> float:
    return sent.est_end_s


def _estimate_off_s(sent: SentFrame, lo: float, hi: float, now: float, time_at=None) -> float:
    """How far (s) the estimate is from having the arm between fractions ``lo`` and ``hi`` of
    ``sent``'s path at ``now`` (0 when it agrees); ``time_at`` as ``_time_window``'s."""
    t_lo, t_hi = _time_window(sent.segment, lo, hi, time_at)
    start = sent.est_end_s - sent.segment.duration_s
    return max(start + t_lo - now, now - (start + t_hi), 0.0)


def _time_window(segment: Segment, lo: float, hi: float, time_at=None) -> tuple[float, float]:
    """Seconds after the segment began between which the arm is at fractions ``lo``…``hi``
    of its path (a path of zero length: the whole segment); ``time_at(segment, fraction)``:
    ``Segment.time_at_fraction`` (the streamer's remembers: ``Streamer._time_at``)."""
    if hi == math.inf:  # no upper end: the arm may be past the frame (``_search``, ``_observe``)
        return _time_window(segment, lo, 0.0, time_at)[0], math.inf
    if segment.length <= 0:
        return 0.0, segment.duration_s
    if time_at is None:
        t_lo = 0.0 if lo <= 0.0 else segment.time_at_fraction(min(lo, 1.0))
        t_hi = segment.duration_s if hi >= 1.0 else segment.time_at_fraction(max(hi, 0.0))
        return t_lo, t_hi
    t_lo = 0.0 if lo <= 0.0 else time_at(segment, min(lo, 1.0))
    t_hi = segment.duration_s if hi >= 1.0 else time_at(segment, max(hi, 0.0))
    return t_lo, t_hi


def _joint_half_fraction(segment: Segment, offset: int, values) -> tuple[float, float] | None:
    """The fractions ``(lo, hi)`` along a joint or still segment between which joints
    offset…offset+2 equal ``values`` within tolerance; None if never (or if the segment is
    Cartesian).  A segment that does not move these joints matches along all its length."""
    if segment.kind not in ("joint", "still"):
        return None
    q0 = segment.start.joints[offset : offset + 3]
    q1 = segment.end.joints[offset : offset + 3]
    dq = [b - a for a, b in zip(q0, q1)]
    span = sum(d * d for d in dq)
    if span <= 1e-12:
        u, slack = 0.0, 1.0
    else:
        u = sum((v - a) * d for v, a, d in zip(values, q0, dq)) / span
        u = min(max(u, 0.0), 1.0)
        slack = JOINT_TOLERANCE_DEG / math.sqrt(span)
    if max(abs(v - (a + d * u)) for v, a, d in zip(values, q0, dq)) > JOINT_TOLERANCE_DEG:
        return None
    return (u - slack, u + slack) if slack < 1.0 else (0.0, 1.0)


def _trace_deviation_mm(segment: Segment, chords: int = 16) -> float:
    """Largest distance between a joint segment's true X/Y/Z trace, sampled at the midpoints of
    ``chords`` equal steps in joint space, and the chords ``distance_to_path`` matches against."""
    worst = 0.0
    for k in range(chords):
        pose = segment.sample(segment.time_at_fraction((k + 0.5) / chords))
        worst = max(worst, distance_to_path(segment, pose.xyz)[0])
    return worst
