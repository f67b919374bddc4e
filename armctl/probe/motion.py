"""The probe's small, announced moves: the speed factor, and the kinematics check.

Strategy: the speed factor is the arm's time over the model's for the same move.  The move
starts when its frame lands (the arm is idle: ``settle``), and every status frame during it is a
sample of the real path: the joint (or the distance from the start) it reports is found on the
model's path at model time τ by bisection, so that sample says ``factor = (t − landing) / τ``,
with t the latest time the frame can have been built (armctl/probe/stream.py: a frame is read
late — behind a USB adapter's 16 ms latency timer, 8 ms on average — and that lateness, taken
for the arm's start delay, made the time bound's tolerance 1.42 where the arm's is 1.05).
Each move is timed there and back, joint and linear, against the model's motion alone (no
``[timing] command_overhead_s``, whatever was kept for the arm).  A straight-line fit
``t = delay + slope × τ`` over a move's samples gives its start delay; the arm's wait before every
command (``command_overhead_s``, armctl/probe/overhead.py: the joint move back goes behind a chain
of delays, whose waits add up in its start) is what the start delays share beyond the probe's lag,
and each move's factor is the least-squares fit through the origin of its samples' time after its
waits (the wait was folded into the factor before: 1.07 on an arm that waits 100 ms).
Resolution: a status step (0.01°, 0.1 mm) against the move's speed, plus
``probe.timestamp_uncertainty_s`` (a real port's reads: 0 on a virtual clock); the stated
precision covers both and the spread of the moves.

Moves (``--no-motion`` runs none): joint 5 by ``JOINT_STEP_DEG`` at ``JOINT_SPEED_DEG_S`` and
back (the tool tip moves by tool length × sin 5°, under 10 mm); then, only if the profile's
kinematics explain the reported X/Y/Z (the linear move's attitude comes from them), the tool
``LINEAR_STEP_MM`` up (or down, if up leaves the workspace) at ``LINEAR_SPEED_MM_MIN`` and back.

Kinematics: at every pose the arm rests in, the profile's forward kinematics of the reported
joints must give the reported X/Y/Z (in robot coordinates: + origin if the status uses the
worktable frame) within ``KINEMATICS_TOLERANCE_MM``.  ``kinematics_verified`` needs two distinct
poses (one could agree by chance): without motion it stays false.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from ..core.kinematics import reach_problem
from ..core.motion import PWM_CHANNEL_COUNT, ArmPose, MotionModel
from ..core.profile_model import SPEED_TOLERANCE_RANGE
from ..core.protocol import JointMove, JointsHighStatus, LinearMove, PositionStatus
from .overhead import Chain, chain_for, measured_wait, overhead_finding
from .plan import LIKELY, SURE, UNSURE, Finding, ProbeStop, Send
from .stream import latest_built_s
from .steps import (  # JOINT_SPEED_DEG_S, ARRIVED_DEG: shared with the restore step's return move
    ARRIVED_DEG, DOCUMENTED, JOINT_SPEED_DEG_S, READBACK_TIMEOUT_S, agreed_joints, settle, wait_until,
)

JOINT_INDEX = 4  # joint 5: the wrist; the tool tip moves least
JOINT_STEP_DEG = 5.0
LINEAR_STEP_MM = 10.0
LINEAR_SPEED_MM_MIN = 300.0
SLOWEST_FACTOR = 4.0  # a move not finished by 4 × the model's time (+ a rotation) is given up
KINEMATICS_TOLERANCE_MM = 1.0
ARRIVED_MM = 0.15
SAMPLE_MARGIN = 3  # samples within this many status steps of either end are left out
# speed_tolerance's least excess over 1: what two small slow moves do not exercise (short fast
# moves, loads).  0.05 keeps 10 ms moves confirmed by time at 91 % of the arm's rate, i.e. 1,000
# of them back and forth never fill a 196-frame FIFO with unproven frames (docs/probe.md).
SPEED_TOLERANCE_MARGIN = 0.05
# A speed factor is sure while its precision (its moves' spread, or the resolution) is within
# SPEED_TOLERANCE_MARGIN of it; likely (stated: speed_tolerance covers it twice over) within this
# share of it; beyond, the moves disagree too much for a value to be stated (``factor_confidence``).
LIKELY_FACTOR_SPREAD = 0.5


def _reported_xyz(probe, since_s: float):
    got = probe.seen.agreed(PositionStatus.KIND, since_s, lambda f: (f.x_mm, f.y_mm, f.z_mm))
    return None if got is None else got[1]


def _robot_xyz(probe, reported):
    if probe.known.status_xyz_frame == "robot":
        return tuple(reported)
    return tuple(r + o for r, o in zip(reported, probe.known.origin_mm))


def record_pose(probe):
    """``yield from`` this with the arm at rest: its joints and X/Y/Z, read fresh, kept for the
    kinematics check."""
    since_s = probe.now_s

    def read():
        return agreed_joints(probe, since_s) is not None and _reported_xyz(probe, since_s) is not None

    if (yield from wait_until(probe, since_s + READBACK_TIMEOUT_S, read)):
        probe.known.poses.append((agreed_joints(probe, since_s), _robot_xyz(probe, _reported_xyz(probe, since_s))))


def kinematics_at_rest(probe):
    yield from settle(probe)
    yield from record_pose(probe)
    return None


def _kinematics_error_mm(probe, joints, robot_xyz) -> float:
    fk = probe.profile.kinematics.forward(joints)
    return math.dist(fk[:3], robot_xyz)


def kinematics_finding(probe):
    poses = probe.known.poses
    default = DOCUMENTED["kinematics_verified"]
    if probe.known.status_xyz_frame is None or not poses:
        return Finding("kinematics_verified", default, None, "no pose with joints and X/Y/Z read", UNSURE)
    errors = [_kinematics_error_mm(probe, joints, xyz) for joints, xyz in poses]
    worst = max(errors)
    distinct = len({tuple(round(j, 1) for j in joints) for joints, _ in poses})
    evidence = (f"forward kinematics of the reported joints vs the reported X/Y/Z at {distinct} distinct pose(s): "
                f"worst {worst:.2f} mm (tolerance {KINEMATICS_TOLERANCE_MM:g} mm)")
    if worst > KINEMATICS_TOLERANCE_MM:
        return Finding("kinematics_verified", default, False, evidence + ": the profile does not describe this arm", SURE)
    if distinct < 2:
        return Finding("kinematics_verified", default, False,
                       evidence + ": they agree, but one pose is not proof (run without --no-motion)", LIKELY)
    return Finding("kinematics_verified", default, True, evidence + ": they agree", SURE)


# --- timed moves ---------------------------------------------------------------------------------


def _invert(segment, progress_of, wanted: float) -> float | None:
    """Model time τ at which ``progress_of(segment.sample(τ))`` reaches ``wanted`` (monotone)."""
    low, high = 0.0, segment.duration_s
    if not progress_of(segment.sample(low)) < wanted < progress_of(segment.sample(high)):
        return None
    for _ in range(50):
        middle = (low + high) / 2
        if progress_of(segment.sample(middle)) < wanted:
            low = middle
        else:
            high = middle
    return (low + high) / 2


@dataclass(frozen=True)
class MoveFit:
    """One timed move: its samples ``(t − landing, τ)``, the factor's relative ``resolution``, its
    ``start_delay_s`` (the intercept) and ``step_s``, one status step's time at its mean speed;
    ``waits``: the per-command waits in its start delay (1, or 1 + a chain's delays: its samples
    then count from the chain's first landing + the delays' model time); ``delay_error_s``: how
    far the intercept may be off either way (a status step — every sample may sit at one phase of
    it — and the landing's uncertainty; the reads' lateness, one way only, apart)."""

    samples: list
    resolution: float
    start_delay_s: float
    step_s: float
    waits: int = 1
    delay_error_s: float = 0.0

    def factor(self, overhead_s: float) -> float:
        """The least-squares factor through the origin of the time after the arm's per-command waits."""
        waited_s = self.waits * overhead_s
        return sum((t - waited_s) * tau for t, tau in self.samples) / sum(tau * tau for _, tau in self.samples)

    def own_delay_s(self, overhead_s: float) -> float:
        """Its start delay less the waits of the chain before it: the move's own."""
        return self.start_delay_s - (self.waits - 1) * overhead_s


def unwaited(profile):
    """``profile`` without a per-command wait: the moves are timed against the model's motion
    alone, whatever a probe kept for the arm before (``[timing] command_overhead_s``)."""
    return replace(profile, timing=replace(profile.timing, command_overhead_s=0.0))


def timed_move(probe, command, start: ArmPose, kind: int, reading, progress_of, arrived, quantum: float,
               chain: Chain | None = None):
    """Send ``command`` (the arm idle at ``start``), follow it to its end; its ``MoveFit``, or None.
    ``reading(frame)`` → a comparable value; ``progress_of(value)`` (also applied to the model's
    poses) → distance from the start.  With a ``chain`` (armctl/probe/overhead.py) its delays go
    first and the move's time counts from the first one's landing + their model time."""
    segment = MotionModel(unwaited(probe.profile), 1.0).plan(command, start)
    written_s = probe.now_s
    delays = chain.commands if chain is not None else ()
    ahead_s = chain.allowed_s if chain is not None else 0.0  # the chain's time, before the move's
    landed_s = at = None
    for sent in (*delays, command):
        landed = yield Send(sent)
        if landed_s is None:  # the first frame's landing: the arm is idle, it starts there
            landed_s, at = landed, probe.wire.written_bytes
            probe.known.moved = True  # (from here: a Ctrl-C meanwhile waits for what was sent)
            probe.known.busy_until_s = landed_s + ahead_s + SLOWEST_FACTOR * segment.duration_s
    limit_s = landed_s + ahead_s + SLOWEST_FACTOR * segment.duration_s + READBACK_TIMEOUT_S

    def done():
        got = probe.seen.agreed(kind, landed_s, reading)
        return got is not None and arrived(got[1])

    ok = yield from wait_until(probe, limit_s, done)
    if not ok:
        raise ProbeStop(f"the arm did not finish a {segment.duration_s:.1f} s move within "
                        f"{SLOWEST_FACTOR:g}× that time: stopped probing")
    arrived_s = probe.seen.agreed(kind, landed_s, reading)[0]
    probe.known.busy_until_s = probe.now_s
    # The move starts when its frame lands: the line model's time, unless the port's reports
    # prove it landed later (a buffer held it); the window they leave counts in the resolution.
    latest_s = probe.landed_by(at, landed_s)
    earliest_s = probe.earliest_landing(at, written_s)
    latest_s = max(earliest_s, latest_s if latest_s is not None else probe.now_s)
    unsure_start_s = 0.0 if earliest_s <= landed_s <= latest_s else latest_s - earliest_s
    landed_s = min(max(landed_s, earliest_s), latest_s)
    origin_s = landed_s + (chain.model_s if chain is not None else 0.0)  # the move's start on an arm with no wait
    total = progress_of(segment.end)
    samples = []
    # the reads' lateness taken out, where the stream proves it
    built_s = latest_built_s(probe.seen.frames, landed_s, probe.profile.connector.status_jitter_ms / 1000)
    for entry in probe.seen.since(kind, landed_s):
        t, frame = entry
        if t > arrived_s:
            break
        t = built_s.get(id(entry), t)
        progress = progress_of(reading(frame))
        if not SAMPLE_MARGIN * quantum < progress < total - SAMPLE_MARGIN * quantum:
            continue
        tau = _invert(segment, lambda pose: progress_of(pose), progress)
        if tau is not None and tau > 0:
            samples.append((t - origin_s, tau))
    slope = total / segment.duration_s
    # a corrupted frame (no checksum, H9) reads anywhere on the path: one 0.335 s in, 1 ms after
    # landing, tilted a fit to a start delay of -23.8 ms (the wait then 0, the factor 1.067 "sure")
    samples = _on_the_line(samples, 2 * quantum / slope + probe.timestamp_uncertainty_s)
    if len(samples) < 3:
        return None
    start_delay_s = _line(samples)[0]
    # one sample's factor error: the status step at the path's slowest sampled speed, and the clock
    # the fit's error bound: half a status step at the mean speed, and the clock, over the longest τ
    resolution = (quantum / 2 / slope + probe.timestamp_uncertainty_s + unsure_start_s) / max(tau for _, tau in samples)
    waits = 1 + (len(chain.commands) if chain is not None else 0)
    return MoveFit(samples, resolution, start_delay_s, quantum / slope, waits, quantum / slope + unsure_start_s)


def _line(samples) -> tuple[float, float]:
    """The straight-line fit ``t = delay + slope × τ`` of ``samples``: (delay, slope).  The delay,
    the intercept, is the start delay: handling before the motion begins, which the fit through
    the origin folds into the factor."""
    mean_t = sum(t for t, _ in samples) / len(samples)
    mean_tau = sum(tau for _, tau in samples) / len(samples)
    spread = sum((tau - mean_tau) ** 2 for _, tau in samples)
    slope = sum((tau - mean_tau) * (t - mean_t) for t, tau in samples) / spread if spread > 0 else mean_t / mean_tau
    return mean_t - slope * mean_tau, slope


def _on_the_line(samples, off_s: float):
    """``samples`` without those more than ``off_s`` off the line the rest fit, the worst left out
    first (at least 3 kept): a sample's honest error is within a status step and the clock's."""
    samples = list(samples)
    while len(samples) > 3:
        delay_s, slope = _line(samples)
        worst = max(samples, key=lambda sample: abs(sample[0] - delay_s - slope * sample[1]))
        if abs(worst[0] - delay_s - slope * worst[1]) <= off_s:
            break
        samples.remove(worst)
    return samples


def _joint_progress(start_joints):
    def progress(value):
        joints = value.joints if isinstance(value, ArmPose) else value
        return abs(joints[JOINT_INDEX] - start_joints[JOINT_INDEX])
    return progress


def _xyz_progress(start_xyz):
    def progress(value):
        xyz = value.robot_cartesian[:3] if isinstance(value, ArmPose) else value
        return math.dist(xyz, start_xyz)
    return progress


def _pose(probe, joints) -> ArmPose:
    known = probe.known
    return ArmPose(probe.profile.kinematics, joints=joints, pwm_us=(float(known.pwm_us),) * PWM_CHANNEL_COUNT,
                   origin_mm=known.origin_mm)


def _joint_moves(probe):
    known = probe.known
    low, high = probe.profile.joint_limits_deg[JOINT_INDEX]
    start = tuple(known.joints_deg)
    step = JOINT_STEP_DEG if start[JOINT_INDEX] + JOINT_STEP_DEG <= high else -JOINT_STEP_DEG
    if not low <= start[JOINT_INDEX] + step <= high:
        return [], "no joint move"  # no room for 5° either way: speed_factor then rests on the linear move alone
    target = list(start)
    target[JOINT_INDEX] += step
    results, no_chain = [], ""
    for there, back in ((start, tuple(target)), (tuple(target), start)):
        command = JointMove(*back, pwm_us=known.pwm_us, speed_deg_s=JOINT_SPEED_DEG_S)
        chain = None
        if results:  # the move back goes behind a chain of delays (armctl/probe/overhead.py)
            chain, no_chain = chain_for(probe, results[0])

        def reading(frame):  # kind 2 carries joints 4…6: placed where JOINT_INDEX finds them
            return (0.0, 0.0, 0.0, frame.j4_deg, frame.j5_deg, frame.j6_deg)

        def arrived(value, back=back):
            return abs(value[JOINT_INDEX] - back[JOINT_INDEX]) <= ARRIVED_DEG

        result = yield from timed_move(probe, command, _pose(probe, there), JointsHighStatus.KIND, reading,
                                       _joint_progress(there), arrived, 0.01, chain)
        yield from record_pose(probe)
        results.append(result)
    return results, no_chain


def _linear_moves(probe):
    known = probe.known
    joints = tuple(known.joints_deg)
    fk = probe.profile.kinematics.forward(joints)
    robot_start = tuple(fk[:3])
    attitude = tuple(fk[3:6])
    for step in (LINEAR_STEP_MM, -LINEAR_STEP_MM):  # up if the profile's workspace and reach allow, else down
        robot_target = (robot_start[0], robot_start[1], robot_start[2] + step)
        target_pose = (*(t - o for t, o in zip(robot_target, known.origin_mm)), *attitude)
        if reach_problem(target_pose, probe.profile, known.origin_mm, near=joints) is None:
            break
    else:
        return []
    results = []
    pose = _pose(probe, joints)
    for there, goal in ((robot_start, robot_target), (robot_target, robot_start)):
        worktable = tuple(g - o for g, o in zip(goal, known.origin_mm))
        command = LinearMove(*worktable, *attitude, pwm_us=known.pwm_us, speed_mm_min=LINEAR_SPEED_MM_MIN)

        def reading(frame):
            return _robot_xyz(probe, (frame.x_mm, frame.y_mm, frame.z_mm))

        def arrived(value, goal=goal):
            return math.dist(value, goal) <= ARRIVED_MM

        result = yield from timed_move(probe, command, pose, PositionStatus.KIND, reading, _xyz_progress(there),
                                       arrived, 0.1)
        pose = MotionModel(probe.profile, 1.0).plan(command, pose).end
        yield from record_pose(probe)
        results.append(result)
    return results


def speed_factor(probe):
    yield from settle(probe)
    default = DOCUMENTED["speed_factor"]
    joint, no_chain = yield from _joint_moves(probe)
    linear = []
    poses = probe.known.poses
    if poses and _kinematics_error_mm(probe, *poses[0]) <= KINEMATICS_TOLERANCE_MM and probe.known.status_xyz_frame:
        linear = yield from _linear_moves(probe)
        linear_note = "" if linear else f"; no linear move: {LINEAR_STEP_MM:g} mm up or down leaves the profile's reach"
    else:
        linear_note = "; no linear move: the profile's kinematics do not explain the reported X/Y/Z, so the tool's attitude is unknown"
    measured = [r for r in joint + linear if r is not None]
    if not measured:
        return Finding("speed_factor", default, None, "too few status samples during the moves", UNSURE)
    wait = measured_wait(measured, no_chain, probe.timestamp_uncertainty_s)
    overhead_s = wait.value_s
    factors = [r.factor(overhead_s) for r in measured]
    value = sum(factors) / len(factors)
    precision = max(max(r.resolution for r in measured), (max(factors) - min(factors)) / 2)
    precision = math.ceil(round(max(precision, 0.005) * 100, 6)) / 100  # up to the next 0.01
    joints = len([r for r in joint if r is not None])  # (measured: the joint moves' first)
    details = {"joint": [round(f, 4) for f in factors[:joints]], "linear": [round(f, 4) for f in factors[joints:]],
               "precision": precision, "start_delay_s": [round(r.own_delay_s(wait.measured_s), 4) for r in measured]}
    evidence = (f"joint 5 ±{JOINT_STEP_DEG:g}° at {JOINT_SPEED_DEG_S:g}°/s: {details['joint']}"
                + (f"; tool ±{LINEAR_STEP_MM:g} mm at {LINEAR_SPEED_MM_MIN:g} mm/min: {details['linear']}" if linear else "")
                + f" (arm time ÷ model time{f' after the {overhead_s * 1000:g} ms wait' if overhead_s else ''}, "
                f"fitted over {sum(len(r.samples) for r in measured)} status samples); ±{precision:g}" + linear_note)
    confidence = factor_confidence(value, precision)
    found = Finding("speed_factor", default, round(value, 3), evidence, confidence, details)
    waited = overhead_finding(wait, measured, confidence)
    left_s = [round(r.own_delay_s(wait.measured_s) - overhead_s, 4) for r in measured]  # (to 0.1 ms, as details shows them)
    return [found, waited, tolerance_finding(value, precision, left_s, overhead_s)]


def factor_confidence(value: float, precision: float) -> str:
    """How sure a speed factor measured ``value`` ± ``precision`` is: sure within
    ``SPEED_TOLERANCE_MARGIN`` of it (what speed_tolerance allows anyway), likely within
    ``LIKELY_FACTOR_SPREAD``, unsure (not stated, not written) beyond."""
    spread = precision / value
    return SURE if spread <= SPEED_TOLERANCE_MARGIN else LIKELY if spread <= LIKELY_FACTOR_SPREAD else UNSURE


def tolerance_finding(value: float, precision: float, start_delays_s, overhead_s: float = 0.0) -> Finding:
    """``speed_tolerance``: how much slower (or faster) than the written speed_factor the arm may
    run, for the streamer's time bound and the loss checks.  It covers the factor's precision
    (twice over), the moves' longest start delay after the wait the model knows (``overhead_s``,
    ``start_delays_s`` are what is left of each move's; the time bound's slack per frame is
    ``(t − 1) × FRAME_SLACK_S / (SLOWEST_ARM_FACTOR − 1)``, so t must give it room) and at least
    ``SPEED_TOLERANCE_MARGIN`` for what two small moves do not exercise; rounded up to 0.01, up to
    the setting's own range (an arm the document's 2.0 is too narrow for needs more, not less).
    No surer than the factor it is relative to (``factor_confidence``): one not stated leaves it
    unsure too, relative to a factor the arm was not shown to have."""
    from ..core.streamer import FRAME_SLACK_S, SLOWEST_ARM_FACTOR

    # the longest: a linear move's fit runs ~5 ms low even on an arm with no delay, so a mean
    # with it under-measures the arm's (10 ms measured 8.5 ms, t 1.43 where 1.5 is needed)
    delay_s = max(0.0, max(start_delays_s))
    excess = max(SPEED_TOLERANCE_MARGIN, 2 * precision / value, delay_s * (SLOWEST_ARM_FACTOR - 1) / FRAME_SLACK_S)
    needed = math.ceil(round((1 + excess) * 100, 6)) / 100
    tolerance = min(SPEED_TOLERANCE_RANGE[1], needed)
    waited = f" after the {overhead_s * 1000:g} ms command_overhead_s" if overhead_s else ""
    evidence = (f"speed_factor ±{precision:g} (twice over: ±{2 * precision / value:.3f} of it), longest start delay "
                f"{delay_s * 1000:.1f} ms{waited}, at least ±{SPEED_TOLERANCE_MARGIN:g}: the time bound confirms a frame "
                f"once an arm {tolerance:g}x slower has finished it")
    confidence = SURE if needed == tolerance else LIKELY
    if needed > tolerance:
        evidence += f" (the arm needs {needed:g}, beyond the setting's range: jobs of short moves may lose frames)"
    factor = factor_confidence(value, precision)
    if factor != SURE:
        confidence = factor  # (likely or unsure: no surer than the factor)
        evidence += f"; relative to a speed_factor that is {factor}"
    return Finding("speed_tolerance", DOCUMENTED["speed_tolerance"], tolerance, evidence, confidence)
