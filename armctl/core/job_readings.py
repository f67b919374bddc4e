"""What the job engine keeps of the arm's reports, and of the frames it wrote: the record the
end of a job (armctl/core/job_end.py) and the arm's arrival (armctl/core/job_arrival.py) judge from.

Strategy: pure state, fed one reading at a time (``Readings.take``: the engine's
``receive_statuses`` calls it for every position, joints and pause-and-PWM report, the kinds
whose readings say whether the arm is at rest); nothing here decides what to write.  From it:

- **At rest** is armctl/core/evidence.py's rule (``known_still_s``): every kind — position, joints
  1-3, joints 4-6, pause and PWM — unchanged since their last change *and* re-read since, from
  the later of that change and the arrival of the last frame written (a frame that came while
  the arm stood still may set it going, its own IK elsewhere, after the readings were taken).
  Until each kind was read once, nothing is known still (``rest_s`` is 0).
- **Paused** is two agreeing pause reports (armctl/core/evidence.py ``agreed``): one corrupted byte
  must never make armctl toggle the arm.
- **Active** (``active_s``): when the arm last visibly worked — position or joints moved by more
  than a reading's jitter (``TARGET_MM``, ``TARGET_DEG``: a reading's resolution, so the arm
  counts as at a target within them), or an SD program's run position advanced while the arm
  stood still.
- **Worked** (``worked_after``): the reports prove the arm worked after a time — one kind's
  readings (position, joints 1-3, joints 4-6), agreed by two reports in a row (armctl/core/evidence.py's
  rule: corrupted reports never agree), came to a value more than a reading's jitter from the
  one they agreed on before, and the arm was last read at that earlier value after that time (a
  reading taken before it may be stale: the kinds come in turn, a rotation apart, and a move
  that ended before may be read only after); or the SD program's run position, agreed so after
  that time, is not the one agreed before (nothing but a program moves it).  What shows that an
  SD program ran and ended (armctl/core/job_arrival.py ``program_ended``): a value agreed on is
  one the arm stopped at.  A program that moves the arm at once shows by its run position alone.
- **Motion** (``motion``): the position and joints alone (no PWM), with when they last changed
  and the latest reading before that which still differed from them — the window in which the
  arm stopped (``Arrival.done_at``).
- **Blips.**  A status frame has no checksum (H9): a corrupted one reads as the arm elsewhere.
  Once the next report of its kind comes back to the value before it, a reading that stood alone
  and that no recent frame's motion explains (``Written.explains``: a wrist turned away and back
  within one rotation is read once, alone, between two readings at its start) is taken for such
  a blip, and the motion, the arm's activity and the last change (``changed_s``, the pause-and-PWM
  kind's apart: two blips that overlap put back neither's) are what they were before it, so the
  arm's time and a "kept working" note never count from a blip.  Which readings: a position or joints reading — or up to
  ``BLIP_READINGS`` in a row, each beyond jitter from the one before (a reading settling within
  jitter is the arm's) — if every other of those kinds that left its value meanwhile came back
  too (a noisy line corrupts two kinds in one rotation now and then; the arm cannot go somewhere
  and come back so fast that the joints, read 30 ms after the position, still read as before; a
  change within jitter still dates the motion: the arm settling, read late); an SD program's run
  position; a pause-and-PWM reading whose pause state no recent frame written toggles and whose
  PWM none sets, each unless it is its neighbours' (a job may toggle its gripper faster than the
  rotation reads it).  A kind that moved for real (read twice where it went, explained, settling,
  away too long) ends the chances of the blips of kinds that left before it: undoing them would
  undo its motion (``Readings.away``).  What the other kinds showed meanwhile still counts.  The
  rest proof stays the careful
  one: ``rest`` dates from the blip's end, a rest is proven REST_CHECK_S after it, and the end of
  the job waits for that proof (armctl/core/job_end.py).  A frame that explains any reading (a
  fixed pose, a joint move from where only the kinematics put the arm) explains none read after
  its motion is proven over (``Written.over``): both joint halves read at its end (two agreeing
  reports each: corrupted ones never agree) after it began — every frame before it known
  finished, or a reading off each one's path, where its span surely holds it (``began_by``).
  Sound: a move to one target reads its target only at its end (or it began there and moves
  nothing), so a later excursion that comes back is no part of it; any other frame that may
  still run explains its own readings as before.  (On pick_and_place's noisy line the arm
  rested at POSE 0 and a corrupted report then counted as its motion: 6 of seeds 1-20 overran.)

``Written`` is the other half of the record: the last ``RECENT_FRAMES`` frames written (the
trailing frames that move nothing are judged on them), the last that moves the arm, the job's
own PAUSE frames, and when the streamer's lower bound passed them (``done``: a frame known
finished explains no later reading, an SD program's whose time bound never runs out included).
A frame whose path is not the planned one (a joint move from a Cartesian end, a move from a
joint end on unverified kinematics) explains any reading, and nothing but time (a start anywhere
within the joint limits: some 30 s) passed it: the arm at rest at the end of exactly one frame
not known finished, in the exact half of each end, proves that one and every one before it ran
(``rests_at``; the engine confirms them, armctl/core/job_arrival.py ``Arrival.rested``).
"""

from __future__ import annotations

import math
from collections import deque
from itertools import islice
from dataclasses import fields
from operator import attrgetter

from .commands import OWN_MOTION_COMMANDS
from .evidence import AGREEING_REPORTS, agreed, known_still_s
from .protocol import (
    CONTROL_COMMANDS, GoToPose, JointMove, JointsHighStatus, JointsLowStatus, PauseStatus, PauseToggle, PositionStatus,
    RunPositionStatus, RunProgram, SetWorktableOrigin,
)
from .streamer import ARRIVAL_SLACK_S
from .streamer.geometry import in_frame

TARGET_MM = 0.5  # how close the reported position must be to the last target (0.1 mm resolution)
TARGET_DEG = 0.2
# The kinds whose readings say whether the arm is at rest — position, joints 1-3, joints 4-6,
# pause and PWM — and their fields, read directly (this runs for every status frame).
REST_VALUES = {cls.KIND: attrgetter(*(f.name for f in fields(cls)))
               for cls in (PositionStatus, JointsLowStatus, JointsHighStatus, PauseStatus)}
RUN_POSITION_KIND = RunPositionStatus.KIND
PAUSE_KIND = PauseStatus.KIND
# How many readings in a row of one kind a blip may be ("Blips"): on a noisy line two corrupted
# reports of one kind come in a row now and then; more would be a kind read wrong, not noise.
BLIP_READINGS = 2
RECENT_FRAMES = 64  # frames written kept for the end of the job (the trailing frames that move nothing)


class Written:
    """The frames the job wrote, as the end of the job needs them (each a ``SentFrame``)."""

    def __init__(self, reports_robot_xyz: bool = False) -> None:
        self.recent: deque = deque(maxlen=RECENT_FRAMES)  # the last frames written
        self.last_move = None  # the last frame written that moves the arm
        self.last_program = None  # the last PROGRAM frame written (its time only the reports tell)
        self.script_toggles: list = []  # the job's own PAUSE frames written, in order
        self.script_paused = False  # the job's own PAUSE lines left the arm to pause: an odd number written
        self.control_sent = 0  # the other control frames written after a first frame (POSE, PROGRAM, G54…: H5 says when they act)
        self.finished: deque = deque(maxlen=RECENT_FRAMES)  # (when, frames known finished by then): ``done``
        self.paths_unknown: deque = deque()  # recent frames whose path is not the planned one (``rests_at``)
        self.open_ends: deque = deque()  # the frames ``over`` may prove over (``ends_exactly``), not yet proven
        self.over_s: dict = {}  # index → when its motion was proven over (``over``): it explains no later reading
        self.reports_robot_xyz = reports_robot_xyz  # the engine's X/Y/Z readings: robot ones less the last frame's origin

    def note(self, sent) -> None:
        self.recent.append(sent)
        command = sent.command
        if isinstance(command, PauseToggle):
            self.script_toggles.append(sent)
            self.script_paused = len(self.script_toggles) % 2 == 1  # (a plain attribute: read for every frame)
        elif sent.index and isinstance(command, CONTROL_COMMANDS):  # (the first frame has no move before it to cut short)
            self.control_sent += 1
        if not sent.path_known:
            self.paths_unknown.append(sent)
        if ends_exactly(sent):
            self.open_ends.append(sent)
            if len(self.open_ends) > RECENT_FRAMES:
                self.open_ends.popleft()
        if sent.segment.moves_reported:  # (``moves_arm``)
            self.last_move = sent
        elif isinstance(command, RunProgram):
            self.last_program = sent

    def done(self, frames: int, now: float) -> None:
        """The streamer's lower bound rose to ``frames`` frames finished at ``now``."""
        self.finished.append((now, frames))

    def rests_at(self, agreed: dict) -> int | None:
        """The frame the arm, at rest, has run through, while a frame whose path is not the planned
        one is not known finished (nothing judges it, and it ``explains`` any reading: the time
        bound of a joint move from a Cartesian end allows a start anywhere, some 30 s) — else
        None.  ``agreed``: for position and both joint halves, the value two reports in a row agree
        on and the arm still reads (not paused).  An arm at rest is at the end of a frame (or at
        the start of the next: the same place), one not known finished or the last that is: if
        that is the end of exactly one of them — each in its exact half: the X/Y/Z of a Cartesian
        target, the joints of a joint one; a frame that moves nothing ends where the one before
        did — that frame and every one before it ran.  An end with no exact half (a fixed pose's,
        an SD program's: the arm's own) could be anywhere: no judgement."""
        done = self.finished[-1][1] if self.finished else 0
        unknown, recent = self.paths_unknown, self.recent
        while unknown and unknown[0].index < done:
            unknown.popleft()  # known finished
        if not unknown or len(agreed) < 3:
            return None
        if done - 1 < recent[0].index and not (done == 0 and recent[0].index == 0):
            return None  # the frame the arm may still rest at the end of is no longer kept
        frames = list(islice(recent, max(done - 1, 0) - recent[0].index, None))
        if any(isinstance(sent.command, OWN_MOTION_COMMANDS) for sent in frames):
            return None
        # (before any frame ran, the arm is at the first one's start: the "end" of frame -1)
        places = [(-1, recent[0].segment.start, True)] if done == 0 else []
        places += [(sent.index, sent.segment.end, sent.segment.moves_reported) for sent in frames]
        origin = recent[-1].segment.end.origin_mm  # the frame the engine reads X/Y/Z in
        match, matched = None, False
        for index, end, moves in places:
            if matched and not moves:
                continue  # (it ends where the frame before did: the same place)
            if not end.xyz_derived:
                xyz = end.xyz  # (reported in the worktable frame in force: this end's, were the arm there)
                if self.reports_robot_xyz:  # (robot X/Y/Z there, read in the last frame's worktable frame)
                    xyz = in_frame(tuple(v + o for v, o in zip(xyz, end.origin_mm)), origin)
                matched = not slot_moved(0, agreed[0], xyz)
            elif not end.joints_derived:
                matched = not (slot_moved(1, agreed[1], end.joints[:3]) or slot_moved(2, agreed[2], end.joints[3:]))
            else:
                return None
            if matched and match is not None:
                return None  # the ends of two frames: which one, the reports cannot say
            if matched:
                match = index
        return match if match is not None and match >= unknown[0].index else None

    def over(self, read: dict) -> None:
        """Prove the motion of each frame of ``open_ends`` over whose end both joint halves have been
        read at after it began (``read``: kind 0, 1, 2 → (the value its last two reports agreed on,
        when the first and the second were read)): a move to one target that reads its target after it began is
        over — it has no other place to go, and if it began there it moves nothing.  From then on it
        explains no reading (``explains``; see "Blips")."""
        low, high = read.get(1), read.get(2)
        if low is None or high is None:
            return
        for sent in tuple(self.open_ends):
            if sent.index < self.done_by(min(low[2], high[2])):
                self.open_ends.remove(sent)  # known finished: it explains nothing now anyway
                continue
            joints = sent.segment.end.joints
            if slot_moved(1, low[0], joints[:3]) or slot_moved(2, high[0], joints[3:]):
                continue
            began_s = self.began_by(sent, read)
            if began_s is None:
                continue
            at_end_s = [first_s if first_s >= began_s else second_s for _, first_s, second_s in (low, high)]
            if min(at_end_s) >= began_s:  # (each half read there after it began: by the first report or the second)
                self.over_s[sent.index] = max(at_end_s)
                self.open_ends.remove(sent)
        while len(self.over_s) > RECENT_FRAMES:
            del self.over_s[next(iter(self.over_s))]

    def began_by(self, frame, read: dict) -> float | None:
        """A time by which ``frame`` had begun, proven by a reading (``read``, as ``over`` takes it)
        read after it landed (the first of its two reports: both read it); None when none proves it.  It had begun once every frame before it
        finished: the frames known finished by then, and each other one by the reading — a frame
        landed runs as soon as the one before it ends, and the arm is on its path while it runs (at
        its start while it waits), so a reading off every one of their paths, each judged in a kind
        whose span surely holds its path (``_span_holds``), says none of them still runs."""
        for kind, (values, read_s, _) in read.items():
            if read_s <= landed_s(frame):
                continue
            done = self.done_by(read_s)
            if done >= frame.index:
                return read_s
            recent = self.recent
            if done < recent[0].index:
                continue  # (a frame not known finished is no longer kept)
            before = islice(recent, done - recent[0].index, frame.index - recent[0].index)
            # (X/Y/Z read in the frame its span is in: the worktable's in force, or the last frame's for robot reports)
            origin = recent[-1].segment.end.origin_mm if self.reports_robot_xyz else None
            if all(sent.certain_end_s < read_s or (sent.path_known and _span_holds(sent.segment, kind, origin)
                                                   and not _in_span(sent.segment, kind, values)) for sent in before):
                return read_s
        return None

    def finished_s(self, frames: int) -> float | None:
        """The earliest time kept by which the lower bound had ``frames`` frames finished (None:
        not kept, or not yet): the arm was past them then."""
        return next((when for when, count in self.finished if count >= frames), None)

    def done_by(self, read_s: float) -> int:
        """The frames known finished by a report read before one read at ``read_s`` (status frames come
        in order: that one was built after it), whatever their time bound."""
        return next((frames for when, frames in reversed(self.finished) if when < read_s), 0)

    def explains(self, kind: int, values: tuple, read_s: float) -> bool:
        """Some recent frame the arm may still have been running at ``read_s`` (its time bound not
        yet run out, and not known finished before: an SD program's or a first move of U/V's bound
        never runs out) passes within a reading's jitter of ``values`` (one kind's readings: 0
        position, 1 and 2 the joint halves): each within the span of its start and end; or is
        one whose motion no model knows (``OWN_MOTION_COMMANDS``, a start a program left)."""
        done = self.done_by(read_s)
        over_s = self.over_s
        for sent in self.recent:
            if sent.certain_end_s < read_s or sent.index < done:
                continue
            if isinstance(sent.command, OWN_MOTION_COMMANDS) or not sent.path_known:
                if over_s and over_s.get(sent.index, read_s) < read_s:
                    continue  # (read at its end after it began: its motion was over, ``over``)
                return True  # (the arm's own motion, or from where a program left it: it may pass anywhere)
            if _in_span(sent.segment, kind, values):
                return True
        return False

    def sets_pwm(self, pwm_us: int) -> bool:
        """Some recent frame written sets a PWM channel to ``pwm_us`` (as the status reports it)."""
        return any(round(value) == pwm_us for sent in self.recent for value in sent.segment.end.pwm_us)

    def toggles_pause(self) -> bool:
        """Some recent frame written toggles the pause state."""
        return any(isinstance(sent.command, PauseToggle) for sent in self.recent)

    def script_pause_line(self):
        return getattr(self.script_toggles[-1].tag, "line", None)


class Readings:
    """The arm's last reports, with when each kind was read and when the readings changed."""

    def __init__(self, written: Written) -> None:
        self.written = written
        # (position, joints 1-3, joints 4-6, pause and PWM as last reported, since when): the
        # arm is at rest when none of them changed for REST_CHECK_S — a wrist turning in place
        # changes only joints.
        self.rest: tuple | None = None
        self.read_at: dict[int, float] = {}  # kind → when it was last read (``known_still_s``)
        self.motion: tuple | None = None  # (position and joints, since when, the latest reading that differed)
        self.moved_from: tuple | None = None  # the readings when they last changed by more than jitter
        self.run_position: float | None = None  # the SD program's run position last reported
        self.changed_s = 0.0  # when any kind's readings last changed, blips left out ("Blips")
        # ... the position's and joints', and the pause-and-PWM kind's: the later of the two is
        # ``changed_s``, and a blip of one puts back only its own (the two overlap on a noisy line)
        self.readings_changed_s = 0.0
        self.other_changed_s = 0.0
        self.motion_active_s: float | None = None  # ``active_s`` by the position and joints, blips left out
        self.program_active_s: float | None = None  # ... by an SD program's run position, blips left out
        self.last_run_change: tuple | None = None  # (the run position before its last change, program_active_s)
        # the position and joints kinds away from their readings, each a blip if it comes back
        # ("Blips"), oldest first: [its kind, its readings before, how many readings since (0:
        # back, waiting for the later ones), what its leaving replaced of motion, moved_from,
        # active_s and readings_changed_s]
        self.away: list = []
        self.last_pause_change: tuple | None = None  # (the readings before, other_changed_s)
        self.settled: tuple | None = None  # the last change within jitter while a kind was away: (when, last read before)
        self.work_s = -math.inf  # the arm worked after this time, by its reports (``worked_after``)
        self.on_rest = None  # told ``Written.rests_at``'s frame (armctl/core/job_arrival.py ``Arrival.rested``)
        # kind → [the value two reports in a row last agreed on, when it was last read there before it
        # changed (else its agreement's first report)]: ``_agreed``
        self.agreed_values: dict = {}
        self.run_position_read_s = 0.0  # when ``run_position`` was read
        self.reported: dict = {}  # kind → its readings (position: in the worktable, ``worktable_xyz``)
        self.pause_reports: deque = deque(maxlen=AGREEING_REPORTS)  # the last pause states reported
        self.pause_read_s: deque = deque(maxlen=AGREEING_REPORTS)  # ... and when they were read
        # kind 0, 1, 2 → (the value its last two reports agreed on, when the first and the second were read): ``over``
        self.agreed_read: dict = {}

    def take(self, kind: int, values: tuple, now: float) -> bool:
        """One kind's readings read at ``now``; True when they changed (or are the first read)."""
        reported, read_at = self.reported, self.read_at
        old = reported.get(kind)
        changed = old != values  # else so are the readings: ``rest`` and ``motion`` hold them
        reported[kind] = values
        before_s = read_at.get(kind)  # the last reading of this kind
        read_at[kind] = now
        agreed = self.agreed_values.get(kind) if kind != PAUSE_KIND else None
        if not changed:  # two reports in a row agree: a new value agreed on may show work (``_agreed``)
            if self.written.open_ends and kind != PAUSE_KIND:
                self.agreed_read[kind] = (values, before_s, now)
                self.written.over(self.agreed_read)
            if kind != PAUSE_KIND and (agreed is None or agreed[0] != values):
                self._agreed(kind, values, before_s, slot_moved)
                if self.written.paths_unknown and self.paused is False and self.on_rest is not None:
                    through = self.written.rests_at(self._agreed_now())
                    if through is not None:
                        self.on_rest(through, now)
            # (a value read twice is no blip: "Blips")
            if kind == PAUSE_KIND:
                self.last_pause_change = None
            elif any(entry[0] == kind and entry[2] for entry in self.away):
                self._moved(kind)  # read twice where it went: no blip
            if self.rest is not None:
                return False
            before_s = None  # (the last reading of this kind that differed: none)
        elif agreed is not None and old == agreed[0]:
            agreed[1] = before_s  # it leaves the value agreed on: last read there then
        # One kind's values changed (or these are the first readings): the readings differ from
        # the last ``rest`` (it always holds the readings before this frame), and so does the
        # motion unless only the pause and PWM changed.
        rest = self.rest = ((reported.get(0), reported.get(1), reported.get(2), reported.get(4)), now)
        motion = self.motion
        if kind == PAUSE_KIND:
            blip = self.last_pause_change
            if (blip is not None and blip[0] == values and (old[0] == values[0] or not self.written.toggles_pause())
                    and (old[1] == values[1] or not self.written.sets_pwm(old[1]))):
                # a pause state or a PWM alone between two equal readings, one no recent frame
                # written sets: a blip
                self.other_changed_s = blip[1]
                self.changed_s = max(self.readings_changed_s, blip[1])
                self.last_pause_change = None
                return True
            self.last_pause_change = (old, self.other_changed_s)
            self.other_changed_s = now
        else:
            away = self.away
            entry = next((entry for entry in away if entry[0] == kind), None)
            if entry is not None:
                if not entry[2]:
                    entry[2] = 1  # away again from where it came back to: one more blip, as the first
                elif self.written.explains(kind, old, before_s):
                    entry = None  # a frame passes there: motion
                elif entry[1] == values:
                    # this kind's readings since it left stood alone between two equal ones
                    entry[2] = 0
                    if away[-1] is entry:
                        # ... and so did those of every kind that left after it: blips (two kinds in
                        # one rotation, or one twice, on a noisy line), which date nothing
                        while away and not away[-1][2]:
                            entry = away.pop()
                        self._undo(entry[3], rest)
                        return True
                    # (a kind that left after it is not back: dated as any change, undone if it comes back)
                elif entry[2] < BLIP_READINGS and slot_moved(kind, old, values):
                    entry[2] += 1  # somewhere else again, where no frame passes either
                else:
                    entry = None  # settling within a reading's jitter, or away too long: motion
                if entry is None:
                    self._moved(kind)
                    away.append([kind, old, 1, (motion, self.moved_from, self.motion_active_s, self.readings_changed_s)])
            elif away and old is not None and not slot_moved(kind, old, values):
                # another kind within a reading's jitter: no excursion, and a blip before it may
                # still be one (the same kind read again near its blip value: that was no blip)
                self.settled = (now, before_s)
            elif old is not None:
                away.append([kind, old, 1, (motion, self.moved_from, self.motion_active_s, self.readings_changed_s)])
            self.readings_changed_s = now
        self.changed_s = now
        if kind != PAUSE_KIND or motion is None:
            moving_s = motion[2] if motion is not None else None
            if kind != PAUSE_KIND and before_s is not None and (moving_s is None or before_s > moving_s):
                moving_s = before_s
            readings = rest[0][:3]
            self.motion = (readings, now, moving_s)
            moved_from = self.moved_from
            # Every other kind's readings are within jitter of ``moved_from`` (checked when they
            # changed, or equal since it was taken): only this kind's can have moved.
            if moved_from is None or (kind != PAUSE_KIND and slot_moved(kind, moved_from[kind], values)):
                self.moved_from = readings
                self.motion_active_s = now
        return True

    def _undo(self, before: tuple, rest: tuple) -> None:
        """Put back what the readings were before a blip (``before``: motion, moved_from, active_s
        and readings_changed_s then), but for another kind's change within jitter meanwhile, which
        still dates the motion (the arm settling, read late); the pause-and-PWM kind's last change
        stays its own (``other_changed_s``: a blip of it meanwhile put back only that)."""
        motion, self.moved_from, self.motion_active_s, changed_s = before
        settled = self.settled
        if settled is not None and settled[0] > changed_s:
            moving_s = settled[1] if motion is None or motion[2] is None else max(settled[1], motion[2])
            motion = (rest[0][:3], settled[0], moving_s)
            changed_s = settled[0]
        self.readings_changed_s = changed_s
        self.changed_s = max(changed_s, self.other_changed_s)
        self.motion = motion

    def _moved(self, kind: int) -> None:
        """``kind`` moved for real: no blip, nor can a blip of a kind that left before it be undone
        (that would undo this motion too)."""
        away = self.away
        del away[:next(k for k, entry in enumerate(away) if entry[0] == kind) + 1]

    @property
    def active_s(self) -> float | None:
        """When the arm last visibly worked: moved, or ran its program (blips left out)."""
        motion_s, program_s = self.motion_active_s, self.program_active_s
        return program_s if motion_s is None else motion_s if program_s is None else max(motion_s, program_s)

    def take_pause(self, paused: bool, now: float) -> bool | None:
        """A pause report read at ``now``; the pause state the reports now agree on (``paused``)."""
        self.pause_reports.append(paused)
        self.pause_read_s.append(now)
        return agreed(self.pause_reports)

    def take_run_position(self, value: float, now: float) -> bool:
        """An SD program's run position; True when it advanced (the arm works, even standing still)."""
        before, before_s = self.run_position, self.run_position_read_s
        advanced = before is not None and value != before
        if advanced:
            last = self.last_run_change
            if last is not None and last[0] == value:  # back where it was before one report: a blip
                self.program_active_s, self.last_run_change = last[1], None
            else:
                self.last_run_change = (before, self.program_active_s)
                self.program_active_s = now
        elif before is not None:
            self.last_run_change = None  # (a value read twice is no blip)
            self._agreed(RUN_POSITION_KIND, value, before_s, _run_position_moved)
        self.run_position, self.run_position_read_s = value, now
        return advanced

    def _agreed(self, kind: int, values, first_s: float, moved) -> None:
        """Two reports of ``kind`` in a row agree on ``values``, the first read at ``first_s``: if
        that is a new value, the arm worked (``worked_after``) — after it was last read at the value
        agreed before (position, joints), or, for the run position, which only a program moves,
        after this one was first read."""
        last = self.agreed_values.get(kind)
        if last is not None and last[0] == values:
            return  # (the same value, agreed again)
        self.agreed_values[kind] = [values, first_s]  # (its first report: the one before this)
        if last is not None and moved(kind, last[0], values):
            since_s = first_s if kind == RUN_POSITION_KIND else last[1]
            if since_s > self.work_s:
                self.work_s = since_s

    def _agreed_now(self) -> dict:
        """Kind → the value two reports in a row agreed on, for the kinds (position, joints) the
        arm still reads at it."""
        reported = self.reported
        return {kind: value[0] for kind, value in self.agreed_values.items()
                if kind in (0, 1, 2) and reported.get(kind) == value[0]}

    def worked_after(self, since_s: float) -> bool:
        """The reports prove the arm worked after ``since_s`` (see "Worked" in the module docstring)."""
        return self.work_s >= since_s

    @property
    def paused(self) -> bool | None:
        """The pause state when the last two pause reports agree (armctl/core/evidence.py ``agreed``)."""
        return agreed(self.pause_reports)

    def rest_s(self) -> float:
        """How long the readings of every kind (position, joints 1-3, joints 4-6, pause and PWM)
        are known unchanged (``known_still_s``; 0 until each kind was read once)."""
        if self.rest is None or len(self.read_at) < len(REST_VALUES):
            return 0.0
        return known_still_s(self.rest_since_s(), self.read_at.values())

    def rest_since_s(self) -> float:
        """Since when the readings prove a rest: their last change, or the arrival of the last
        frame written if later — a frame that came while the arm stood still may set it going
        (its own IK elsewhere) after the readings were taken."""
        since = self.rest[1]
        recent = self.written.recent
        if recent:
            since = max(since, landed_s(recent[-1]))
        return since

    @property
    def position(self) -> tuple | None:
        return self.reported.get(0)

    @property
    def joints(self) -> tuple:
        """The six joints as last reported (fewer while a half was never read)."""
        return (self.reported.get(1) or ()) + (self.reported.get(2) or ())


def _in_span(segment, kind: int, values: tuple) -> bool:
    """One kind's readings (0 position, 1 and 2 the joint halves) within a reading's jitter of the
    span of ``segment``'s start and end in that kind."""
    limit = TARGET_MM if kind == 0 else TARGET_DEG
    start, end = segment.start, segment.end
    if kind == 0:
        a, b = start.xyz, end.xyz
    else:
        first = 3 * (kind - 1)
        a, b = start.joints[first:first + 3], end.joints[first:first + 3]
    return all(min(p, q) - limit <= v <= max(p, q) + limit for p, q, v in zip(a, b, values))


def _span_holds(segment, kind: int, origin: tuple | None = None) -> bool:
    """The span of ``segment``'s start and end in ``kind`` (``_in_span``) holds its whole path, as the
    arm runs it: a line's or a still frame's X/Y/Z, a joint move's or a still frame's joints (a
    straight line in that space), each where the job knows both ends exactly (not from the
    profile's kinematics), the X/Y/Z in one worktable frame (``origin``, when not None: the one the
    readings are in).  An arc's path leaves its ends' span; a line's joints may too."""
    start, end = segment.start, segment.end
    if kind == 0:
        return (segment.kind in ("line", "still") and not (start.xyz_derived or end.xyz_derived)
                and start.origin_mm == end.origin_mm and origin in (None, end.origin_mm))
    return segment.kind in ("joint", "still") and not (start.joints_derived or end.joints_derived)


def ends_exactly(sent) -> bool:
    """A frame that explains any reading (``Written.explains``: the arm's own motion, or a path not
    the planned one) whose end the job knows in joints — a fixed pose's (the profile's), a joint
    move's: ``Written.over`` may prove its motion over."""
    return (isinstance(sent.command, (GoToPose, JointMove)) and not sent.segment.end.joints_derived
            and (isinstance(sent.command, GoToPose) or not sent.path_known))


def landed_s(sent) -> float:
    """When a frame written has surely landed: its last byte left the wire, plus ``ARRIVAL_SLACK_S``."""
    return sent.wire_end_s + ARRIVAL_SLACK_S


def _run_position_moved(kind: int, old: float, new: float) -> bool:
    """The run position changed (``_agreed``'s test for it; a program's position has no jitter)."""
    return old != new


def values_text(values) -> str:
    return ", ".join(f"{v:.1f}" for v in values or ())


def moves_arm(segment) -> bool:
    """Whether a frame's motion changes the reported position or joints (the motion model's
    ``Segment.moves_reported``: not a move of E0/E1 alone, which no status kind reports)."""
    return segment.moves_reported


def changes_readings(sent) -> bool:
    """Whether the position or joint readings may change while a frame written runs, or as it
    acts: it moves the arm (``moves_arm``), its path is not the planned one (it starts where only
    the profile's kinematics or an SD program put the arm), its motion is the arm's own
    (``OWN_MOTION_COMMANDS``), or it sets the worktable origin the X/Y/Z are reported in (G54).
    A delay, an M code or a PWM change does none of these."""
    return moves_arm(sent.segment) or not sent.path_known or isinstance(sent.command, _READINGS_COMMANDS)


_READINGS_COMMANDS = OWN_MOTION_COMMANDS + (SetWorktableOrigin,)


def moved_clearly(before: tuple, after: tuple) -> bool:
    """Position (kind 0) or joints (kinds 1, 2) changed by more than a reading's jitter."""
    return any(slot_moved(kind, old, new) for kind, (old, new) in enumerate(zip(before, after)))


def slot_moved(kind: int, old: tuple | None, new: tuple | None) -> bool:
    """One kind's readings (0 position, 1 and 2 the joint halves) changed by more than jitter."""
    if old is None or new is None:
        return old is not new
    limit = TARGET_MM if kind == 0 else TARGET_DEG  # unrolled (three readings a kind): every moving status frame
    a, b, c = old
    x, y, z = new
    return abs(a - x) > limit or abs(b - y) > limit or abs(c - z) > limit
