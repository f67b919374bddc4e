"""The pacing core: when may the next frame be written to an arm that never acknowledges?

Strategy: pure — status frames, writes and ``now`` come in as arguments; decisions come out.
The connector holds at most ``fifo_frames`` frames behind the one executing (the profile's
``[connector]`` table; 200 by the document) and silently drops the rest, and the arm says only
where it is.  What the document leaves open is read from the profile, never assumed here:
``fifo_frames`` (the capacity), ``speed_factor`` (in the motion model's durations),
``status_xyz_frame`` (robot-frame X/Y/Z are turned into the worktable frame of the segment they
are matched against) and ``kinematics_verified`` (below).  So for every frame written the
streamer keeps its planned ``Segment`` (the shared motion-time model), the moment its last byte
left the wire, and two views of the arm:

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
    never confirms it (``TimeBound.allowance_s``) — a later frame's sighting or the arm at rest does;
    nor the first move that sets E0/E1, which no status reports: from where they stood, its time
    may be any (``TimeBound.moves_e_from_the_start``; no pace is measured on it either); nor a
    PROGRAM frame, whose SD program runs as long as it says while the frames behind it wait in
    the FIFO (``TimeBound.program_time_unknown``), and the first move after it starts where
    the program left the arm (``TimeBound.starts_where_a_program_left``: a joint move from
    anywhere, a Cartesian one never by time; its path is not the planned one).
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
    arm (``Estimate.arm_ends``), since the estimate runs at the model's pace through frames no sighting
    re-times.  A frame is also allowed once no more than ``FEED_AHEAD_S`` (or the lead) of the
    arm's seconds is queued in all, so the arm is never starved of a move longer than the lead
    by itself — and, behind a first pending frame not yet begun (written ahead), only once it
    begins.  The pace shapes only this rule (and ``queued_seconds``): the lower bound never
    reads it.
(c) with ``control_frames = "arrival"`` a control frame (POSE, PROGRAM, G54, a pause toggle…)
    acts the moment it lands, ahead of everything queued: one in a job is written only once the
    lower bound says every frame before it has finished, so the arm runs the job in its order —
    and a PROGRAM has finished only when its SD program has: the lower bound passes it only on
    the arm's reports (it worked after the frame landed and rests since, or a later frame's
    sighting), never on time, so the next control frame cannot cut the program short.

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
  frame and every later one (``TimeBound.allow_pace``: only ever more careful), so an arm 1.3x or
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

Why it decided is data too, for whoever drives it (armctl/host/runner.py logs it with ``-v``):
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

The parts (each owns its state; ``Streamer``, the façade, routes events and owns no rule):

  ledger.py      ``Ledger``     the frames written and not known consumed (``pending``), the
                                lower bound, and what proved each frame consumed
  evidence.py    ``Sightings``  which pending frames a report may lie on (a ``Sighting``)
  time_bound.py  ``TimeBound``  the slow-arm deadline chain and the arm-running clock
  estimate.py    ``Estimate``   the re-anchored end of each frame, the measured pace
  losses.py      ``Losses``     the signs of loss, each with its evidence
  gate.py        ``Gate``       the write rules (a)–(c), the plan of the next frame, the wire
  facade.py      ``Streamer``   the callers' one object: a write to every part, a report to
                                the evidence and from its ``Sighting`` to the rest
  frames.py, geometry.py, constants.py   the records, path/time geometry and numbers they share

Soundness, written once
=======================

The streamer's one promise is rule (a): it never writes a frame the FIFO has no room for, so
everything rests on ``consumed_lower_bound`` never passing the frames that have really left the
FIFO.  Each part may conclude only what its evidence says; this is the whole list.

1. *A frame left the FIFO* (the ledger pops it; nothing else does), on exactly three grounds:

   a. **An agreed sighting** (``Sightings`` → ``Streamer._take`` → ``Ledger.consume_before``): a
      report and the last one of the same stream (position, joints 1–3, joints 4–6) that a
      search judged each lie on the path of a pending frame, and the bound moves to the smaller
      of the two earliest such frames — every frame before it has finished, because the arm runs
      its frames in order and this one's path holds the arm.  Only the earliest candidate counts
      (a point on several pending paths proves the first); a stream searches only the frames it
      can judge (X/Y/Z stops at a frame whose X/Y/Z only unverified kinematics know, counting on
      a move from its end but never past it; joint halves stop at the first Cartesian frame and
      count on a joint move from a Cartesian end but never past it); a match beyond the part of
      the queue not searched proves only that part's first frame; an arc's G300 is never
      confirmed by its arc alone (``group_index``).  One corrupted report cannot move the bound
      (agreement), a lost one only delays it.
   b. **Time** (``TimeBound.advance``): the head frame's deadline has passed on the arm-running
      clock — the time of the last kind-4 report that said running; a paused or silent arm stops
      the clock, and a resume moves every deadline back by the whole pause.  A deadline chains
      from frame to frame: no sooner than the frame landed (``ARRIVAL_SLACK_S`` after its last
      byte) nor than the frame before surely ended, plus its model duration and its allowance
      (``allowance_s``: a longer path from an unverified start) times ``slowest_factor``, plus
      ``frame_slack_s``.  This rests on one hypothesis, the profile's ``speed_tolerance`` (the
      arm never that much slower than the model), and the chain only ever loosens on a measured
      pace (``allow_pace``); it tightens only on an agreed sighting that frame k has begun, from
      the least fraction of k's path both reports allow (``restart``), or on the arm seen at
      rest mid-job (``at_rest``).  Never on time: a frame whose time may be any (an arc from an
      unverified start, the first move of E0/E1, a PROGRAM and a Cartesian move
      after it: deadline infinite), a G300 before its G301 lands, a frame a RESET CONNECTOR
      may have cleared, and nothing at all once the FIFO may have been cleared (``cleared``).
   c. **The arm at rest** (``Streamer.confirm_all_done``): on the caller's proof (armctl/core/job.py:
      every status kind re-read unchanged at the last frame's target), every frame written, or
      those before ``before`` — never a trailing G300.  Held behind a PROGRAM (its time
      unknown), the caller's proof is its own (armctl/core/job_program.py): the arm
      worked after the frame landed — a kind's reports agreed on a new value, two in a row
      (armctl/core/job_readings.py ``worked_after``) — and is at rest since, wherever; that
      confirms the frames through it.

   Left the FIFO is not *ran*: a report on a later frame counts a frame ``confirmed_by_reports``
   only when the caller says the FIFO holds every frame the capacity rule lets in
   (``fifo_holds_all``) and no RESET CONNECTOR may have cleared it, or when the arm rests at its
   very target and could rest there no other way (``evidence.ran_at_rest``); else it is
   ``confirmed_unseen``.  Time alone is ``confirmed_by_time``.  Nor is *left* always *ran*: a
   target out of the arm's reach is refused and leaves the FIFO unrun, which only the not-begun
   sign and the gaps (4.) see; a straight move of ``RUN_PROOF_MIN_S`` or more they cannot judge
   (its start only the profile's kinematics know, or a frame whose X/Y/Z no report judges
   queued behind it), and a shorter one anywhere whose target the profile's kinematics cannot
   take (``Sightings.may_refuse``: refused, the arm runs on at once, which no sign sees), counts
   as run only on two reports on its path, or inside the next line's off the way the arm would
   take there from its start, so the next began at its target (``Ledger.prove_ran``) — else
   ``runs_unproven`` names it and the job may not end "finished".

2. *Where the arm probably is* (``Estimate``): from the model's times, re-anchored on every
   sighting, agreed or not, even past a frame the stream cannot judge (``reanchor_beyond``).
   It proves nothing: it feeds only rule (b), ``queued_seconds`` and the pin the pace follows.
   A wrong estimate costs pace or a longer stop, never a frame: rule (a) reads the bound alone.

3. *How much slower than the model the arm runs* (``Estimate.pace``): from two agreed sightings
   of one stream inside the moving path of one frame whose time is known, at least
   ``PACE_MIN_SPAN_S`` of model time apart, no pause between; the largest of the last few,
   never below 1 nor above ``PACE_MAX``.  The lead follows it (in model seconds it is the lead
   ÷ the pace); the time bound only ever widens on it (``allow_pace``), never narrows when an
   old sample ages out.

4. *The arm skipped frames or broke the hypothesis* (``Losses``), never from one report:
   a **gap** — between two agreed sightings less time passed (plus ``LOSS_SLACK_S``) than the
   motion between takes even ``speed_tolerance`` times faster than the model, counting only
   frames whose length the plan knows and the earlier sighting at the latest frame it may lie
   on; a **reversal** — two reports in a row inside a finished frame's path and on no pending
   path; **slowness** — pairs of agreed sightings along one frame (a status period of slack at
   each end) slower than the tolerance, on no later frame through the same point, told at the
   end only when time confirmed frames at a narrower factor and was still trusted; a move **not
   begun** — two position reports sampled after the head frame's time bound still at its start
   and on no later frame (a target the arm refused: tests/test_sim_reach.py).  Losses move
   neither the bound nor the estimate — except that time waits for those two reports before it
   counts such a frame done (only ever later) — they change what the job may claim (``losses``,
   ``first_suspect_index``).

5. *The next frame may go* (``Gate``): rules (a)–(c) above, from the bound (a, c) and the
   estimate and pace (b) — so the FIFO bound holds whatever the estimate says.
"""

from __future__ import annotations

from ..armstate import ROTATION_S
from .constants import (
    ARRIVAL_SLACK_S,
    CAPACITY_MARGIN_FRAMES,
    DEFAULT_LEAD_S,
    FASTEST_ARM_FACTOR,
    FEED_AHEAD_S,
    FRAME_SLACK_S,
    JOINT_TOLERANCE_DEG,
    JOINT_TRACE_FRACTION,
    JOINT_TRACE_SLACK,
    LOSS_SLACK_S,
    PACE_FOLLOWED,
    PACE_MAX,
    PACE_MIN_SPAN_S,
    PACE_SAMPLES,
    POSITION_TOLERANCE_MM,
    RECENT_SENT_FRAMES,
    SCAN_WINDOW_FRAMES,
    SLOWEST_ARM_FACTOR,
    UNVERIFIED_FK_SHARE,
    frame_slack_s,
    limit_frames,
)
from .facade import Streamer
from .frames import Evidence, SentFrame, WaitReason

__all__ = [
    "ARRIVAL_SLACK_S", "CAPACITY_MARGIN_FRAMES", "DEFAULT_LEAD_S", "FASTEST_ARM_FACTOR", "FEED_AHEAD_S",
    "FRAME_SLACK_S", "JOINT_TOLERANCE_DEG", "JOINT_TRACE_FRACTION", "JOINT_TRACE_SLACK", "LOSS_SLACK_S",
    "PACE_FOLLOWED", "PACE_MAX", "PACE_MIN_SPAN_S", "PACE_SAMPLES", "POSITION_TOLERANCE_MM",
    "RECENT_SENT_FRAMES", "ROTATION_S", "SCAN_WINDOW_FRAMES", "SLOWEST_ARM_FACTOR", "UNVERIFIED_FK_SHARE",
    "Evidence", "SentFrame", "Streamer", "WaitReason", "frame_slack_s", "limit_frames",
]
