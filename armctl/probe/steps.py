"""The probe's measurements that need no motion: listen, the encoding (H1/H8) and the status
frame after G54, control-frame timing (H5); and the restore step, with the
move back to the joints the arm started at after armctl/probe/motion.py's moves (motion.py
imports from here, never the other way).

Strategy: each step is a generator over ``plan.Probe`` (see plan.py).  Every frame sent here
leaves the arm where it is: G54 changes only the frame of reference (read back through kind
3), a delay (G4) only holds the arm, a pause toggle only freezes what runs (read back through
kind 4).  Every value read is trusted only once ``AGREEING_FRAMES`` frames in a row agree.
``Known`` holds what the arm reported at the start and what the probe has changed, so the
restore step (also run on Ctrl-C) can put it back.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from dataclasses import dataclass, field

from ..core.evidence import agreeing_runs
from ..core.protocol import (
    PWM_RANGE_US,
    STATUS_PERIOD_S,
    STATUS_ROTATION,
    Delay,
    JointMove,
    JointsHighStatus,
    JointsLowStatus,
    PauseStatus,
    PauseToggle,
    PositionStatus,
    SetWorktableOrigin,
    WorktableStatus,
)
from .plan import SURE, UNSURE, Finding, ProbeStop, Send, Wait, paused_of, pwm_of, xyz_of

LISTEN_S = 1.0  # ≥ 3 rotations of 9 kinds at 30 ms
FIRST_STATUS_TIMEOUT_S = 4.0
READBACK_TIMEOUT_S = 2.5  # a value written, read back: ~1 rotation, a few lost frames
CONTROL_DELAY_S = 2.0  # the delay a pause toggle is written behind
# An arm that acts on arrival confirms the pause (two kind-4 frames) within 2 rotations of the
# toggle's landing; one more for lost status frames.
ARRIVAL_CONFIRM_ROTATIONS = 3
QUIET_S = 1.5  # nothing the arm reports changes for this long: it has done what it was sent
QUIET_LIMIT_S = 60.0  # restoring waits at most this long for queued frames to finish
ORIGIN_OFFSET_MM = (123.4, 56.7, 28.9)  # G54 test origin: negative, fractional, far from the old
ORIGIN_TOLERANCE_MM = 0.051  # one status step (0.1 mm) rounds to ±0.05
STILL_TOLERANCE_DEG = 0.02
STILL_SPAN_S = 0.5  # the joints read the same over at least this long: the arm is still
GRIPPER_SPEED_DEG_S = 10.0  # joint speed of a PWM-only frame (nothing moves; the slot needs a value)
# The probe's slow joint moves (motion.py's measuring moves, and the restore step's move back to
# the joints the arm started at) and when a joint has arrived.
JOINT_SPEED_DEG_S = 2.0
ARRIVED_DEG = 0.02

def _documented() -> dict:
    """The document's readings: the packaged profile's [connector] table and the per-command wait
    (one place)."""
    from ..host.profile import CONNECTOR_KEYS, default_profile

    profile = default_profile()
    return {**{key: getattr(profile.connector, key) for key in CONNECTOR_KEYS},
            "command_overhead_s": profile.timing.command_overhead_s}


DOCUMENTED = _documented()


@dataclass
class Known:
    """The arm as the probe found it, and what the probe has changed since."""

    xyz_mm: tuple[float, float, float]
    joints_deg: tuple[float, ...]
    origin_mm: tuple[float, float, float]
    pwm_us: int
    float_order: str = "<"  # H1; ">" once the arm shows it reads floats big-endian
    busy_until_s: float = 0.0  # every frame sent has finished by then (model time)
    # a step whose frames' time shows only as the arm runs them (a FIFO round's fillers, at the pace
    # its reports show): when they may have run, asked anew (the restore step waits for it)
    queued_until_s: Callable[[], float] | None = None
    status_xyz_frame: str | None = None
    moved: bool = False  # a motion step ran: the restore step compares the joints
    poses: list = field(default_factory=list)  # (joints, robot X/Y/Z) where the arm rested


def agreed_joints(probe, since_s: float, until_s: float = float("inf")):
    low = probe.seen.agreed(JointsLowStatus.KIND, since_s, lambda f: (f.j1_deg, f.j2_deg, f.j3_deg), until_s)
    high = probe.seen.agreed(JointsHighStatus.KIND, since_s, lambda f: (f.j4_deg, f.j5_deg, f.j6_deg), until_s)
    if low is None or high is None:
        return None
    return (*low[1], *high[1])


def _readings(probe, since_s: float) -> dict | None:
    seen = probe.seen
    xyz = seen.agreed(PositionStatus.KIND, since_s, xyz_of)
    origin = seen.agreed(WorktableStatus.KIND, since_s, xyz_of)
    pause = seen.agreed(PauseStatus.KIND, since_s, lambda f: (f.paused, f.pwm_us))
    joints = agreed_joints(probe, since_s)
    if None in (xyz, origin, pause, joints):
        return None
    return {"xyz": xyz[1], "origin": origin[1], "paused": pause[1][0], "pwm": pause[1][1], "joints": joints}


def wait_until(probe, until_s: float, ready=None):
    """``yield from`` this: wait for ``ready()`` or ``until_s``; whether ``ready()`` holds."""
    yield Wait(until_s, ready)
    return ready() if ready is not None else True


def settle(probe):
    """Wait until everything sent has finished (the probe's own model of what it sent)."""
    if probe.now_s < probe.known.busy_until_s:
        yield Wait(probe.known.busy_until_s)


# --- listen --------------------------------------------------------------------------------------


def _stillness(probe, since_s: float) -> bool | None:
    """True: every agreed joint reading since ``since_s`` is the same, over ≥ ``STILL_SPAN_S``;
    False: two differ (the arm moves); None: not enough readings yet."""
    spans = []
    for kind, key in ((JointsLowStatus.KIND, lambda f: (f.j1_deg, f.j2_deg, f.j3_deg)),
                      (JointsHighStatus.KIND, lambda f: (f.j4_deg, f.j5_deg, f.j6_deg))):
        runs = probe.seen.agreed_runs(kind, since_s, key)
        if any(max(abs(a - b) for a, b in zip(runs[0][1], value)) > STILL_TOLERANCE_DEG for _, value in runs):
            return False
        last_s = probe.seen.by_kind[kind][-1][0] if runs else 0.0
        spans.append(last_s - runs[0][0] if runs else 0.0)
    return True if min(spans) >= STILL_SPAN_S else None


def listen(probe):
    start_s = probe.now_s
    yield Wait(start_s + LISTEN_S)

    def enough():
        return _readings(probe, start_s) is not None and _stillness(probe, start_s) is not None

    if not enough() and _stillness(probe, start_s) is not False:
        yield Wait(start_s + FIRST_STATUS_TIMEOUT_S, lambda: enough() or _stillness(probe, start_s) is False)
    found = _readings(probe, start_s)
    kinds = sorted({frame.KIND for _, frame in probe.seen.frames})
    joints_read = {JointsLowStatus.KIND, JointsHighStatus.KIND} <= set(kinds)
    if _stillness(probe, start_s) is not True and joints_read:
        raise ProbeStop("the arm is moving (its joints do not read the same twice in a row): wait until it is "
                        "still, then probe again")
    if found is None:
        raise ProbeStop(f"the arm's status did not show its pose, origin and PWM within {FIRST_STATUS_TIMEOUT_S:g} s "
                        f"(kinds read: {kinds or 'none'}): is the arm on, and the baud rate right?")
    if found["paused"]:
        raise ProbeStop("the arm reports it is paused: resume it (or reset it) and probe again; "
                        "the probe sends nothing to a paused arm")
    low, high = PWM_RANGE_US
    if not low <= found["pwm"] <= high:
        raise ProbeStop(f"the arm reports PWM {found['pwm']} µs, outside {low:g}…{high:g}: the probe could not "
                        "put it back; set the gripper first (e.g. `armctl jog`)")
    probe.known = Known(found["xyz"], found["joints"], found["origin"], found["pwm"], busy_until_s=probe.now_s)
    return None


# --- H1/H8 and the status frame after G54 -------------------------------------------------------


def test_origin(origin_mm) -> tuple[float, float, float]:
    """Negative and fractional (a sign or byte-order mistake cannot look right), ≥ 28.9 mm away."""
    return tuple(round(-(abs(o) + d), 1) for o, d in zip(origin_mm, ORIGIN_OFFSET_MM))


def origin_frame(origin_mm, float_order: str) -> bytes:
    """A G54 frame, its floats in ``float_order`` (``<`` is H1; ``>`` only to undo a mistake)."""
    raw = bytearray(SetWorktableOrigin(*origin_mm).encode())
    if float_order != "<":
        for k in range(3):
            raw[3 + 4 * k : 7 + 4 * k] = struct.pack(">f", origin_mm[k])
    return bytes(raw)


def _close(a, b, tolerance: float) -> bool:
    return all(abs(x - y) <= tolerance for x, y in zip(a, b))


def _big_endian_reading(value: float) -> float:
    read = struct.unpack(">f", struct.pack("<f", value))[0]
    return read if math.isfinite(read) else math.inf


def diagnose_origin(sent, got) -> tuple[str, str | None]:
    """Why kind 3 reports ``got`` after G54 ``sent``: an explanation, and the float order to
    undo it with (None when the origin cannot be put back by the probe)."""
    as_big = [_big_endian_reading(v) for v in sent]
    if all(abs(b) > 3276.7 or abs(b - g) <= 0.051 for b, g in zip(as_big, got)) and any(abs(b) <= 3276.7 for b in as_big):
        return ("H1 is wrong: the arm reads the frame's floats big-endian (it reports the origin the bytes of "
                f"{tuple(sent)} spell in big-endian order). armctl encodes every float little-endian, so every "
                "coordinate it sends would be garbage to this arm"), ">"
    if all(abs(v) < 1e-30 for v in as_big) and all(abs(g) <= 0.051 for g in got):
        return ("H1 is wrong: the arm reads the frame's floats big-endian (our little-endian floats read as "
                "~0 to it, and it reports an origin of 0)"), ">"
    if all(g >= 0 for g in got) and _close([g - 6553.6 for g in got], sent, 0.051):
        return "H8 is wrong: the arm's status words are unsigned (a negative origin came back as 65536 − |value|)", "<"
    for scale in (10.0, 0.1, 100.0, 0.01):
        if _close([g * scale for g in got], sent, 0.051 * abs(scale)):
            return f"H8 is wrong: the status words' scale differs by ×{1 / scale:g} from the document's ÷10 mm", "<"
    return (f"the arm reports origin {tuple(got)} after G54 {tuple(sent)}: the float byte order (H1) or the sign/scale "
            "of the status words (H8) differs from the document"), None


def encoding(probe):
    """G54 to a test origin, read back through kind 3 (H1, H8); kind 0 before and after says
    which frame the status X/Y/Z uses; then G54 back."""
    known = probe.known
    target = test_origin(known.origin_mm)
    before = probe.seen.agreed(PositionStatus.KIND, probe.now_s - LISTEN_S, xyz_of)
    landed_s = yield Send(SetWorktableOrigin(*target))
    known.busy_until_s = landed_s

    def changed():
        got = probe.seen.agreed(WorktableStatus.KIND, landed_s, xyz_of)
        return got is not None and not _close(got[1], known.origin_mm, ORIGIN_TOLERANCE_MM)

    yield from wait_until(probe, landed_s + READBACK_TIMEOUT_S, changed)
    got = probe.seen.agreed(WorktableStatus.KIND, landed_s, xyz_of)
    if got is None or not changed():
        raise ProbeStop(f"the arm did not take the worktable origin (G54) frame: status kind 3 still reports "
                        f"{known.origin_mm} {READBACK_TIMEOUT_S:g} s after it; check the port and baud rate")
    changed_s, reported = got
    if not _close(reported, target, ORIGIN_TOLERANCE_MM):
        message, order = diagnose_origin(target, reported)
        if order is not None:
            known.float_order = order
        raise ProbeStop(message)
    encoding_finding = Finding(
        "encoding", "H1 little-endian floats, H8 signed words ÷10", "as documented",
        f"G54 to {target} was reported back through status kind 3 as {reported}", SURE)
    # Kind 0 after the change: the worktable frame moves it by old − new origin; the robot frame not.
    yield from wait_until(probe, changed_s + READBACK_TIMEOUT_S,
                          lambda: probe.seen.agreed(PositionStatus.KIND, changed_s, xyz_of) is not None)
    after = probe.seen.agreed(PositionStatus.KIND, changed_s, xyz_of)
    frame_finding = _status_frame_finding(known, target, before, after)
    yield from put_origin_back(probe)
    return [encoding_finding, frame_finding]


def _status_frame_finding(known, target, before, after) -> Finding:
    default = DOCUMENTED["status_xyz_frame"]
    if before is None or after is None:
        return Finding("status_xyz_frame", default, None, "status kind 0 was not read before and after G54", UNSURE)
    shift = tuple(round(o - t, 1) for o, t in zip(known.origin_mm, target))
    expected_worktable = tuple(b + s for b, s in zip(before[1], shift))
    tolerance = 2 * ORIGIN_TOLERANCE_MM
    evidence = f"X/Y/Z (kind 0) {before[1]} before G54 moved the origin by {tuple(-s for s in shift)} mm, {after[1]} after"
    if _close(after[1], expected_worktable, tolerance):
        known.status_xyz_frame = "worktable"
        return Finding("status_xyz_frame", default, "worktable", evidence + ": it follows the worktable origin", SURE)
    if _close(after[1], before[1], tolerance):
        known.status_xyz_frame = "robot"
        return Finding("status_xyz_frame", default, "robot", evidence + ": unchanged, robot coordinates", SURE)
    return Finding("status_xyz_frame", default, None, evidence + ": neither frame explains it (did the arm move?)", UNSURE)


def put_origin_back(probe):
    known = probe.known
    landed_s = yield Send(SetWorktableOrigin(*known.origin_mm), origin_frame(known.origin_mm, known.float_order))
    known.busy_until_s = max(known.busy_until_s, landed_s)
    ok = yield from wait_until(probe, landed_s + READBACK_TIMEOUT_S, lambda: _origin_is(probe, landed_s, known.origin_mm))
    if not ok:
        raise ProbeStop(f"the worktable origin could not be put back to {known.origin_mm}: set it with G54")
    _note(probe, f"worktable origin put back to {known.origin_mm}")


def _origin_is(probe, since_s: float, origin_mm) -> bool:
    got = probe.seen.agreed(WorktableStatus.KIND, since_s, xyz_of)
    return got is not None and _close(got[1], origin_mm, ORIGIN_TOLERANCE_MM)


def _note(probe, text: str) -> None:
    if text not in probe.notes:
        probe.notes.append(text)


# --- control frames: queued (H5) or on arrival ----------------------------------------------------


def _paused_since(probe, since_s: float):
    """(time of the first paused frame, time the second one confirmed it) of the first run of
    ``AGREEING_FRAMES`` paused kind-4 frames since ``since_s``, or None (armctl/core/evidence.py
    ``agreeing_runs``).  The confirmation time is what the control test judges by: one corrupted
    frame can make a run begin early, never confirm it."""
    readings = ((t, frame.paused) for t, frame in probe.seen.since(PauseStatus.KIND, since_s))
    return next(((start_s, confirmed_s) for start_s, confirmed_s, paused in agreeing_runs(readings) if paused), None)


def _running_since(probe, since_s: float) -> bool:
    got = probe.seen.agreed(PauseStatus.KIND, since_s, paused_of)
    return got is not None and not got[1]


def control(probe):
    """A pause toggle written behind a delay: paused while the delay runs → arrival; paused when
    it ends → queued (H5).  Then the resume toggle."""
    known = probe.known
    yield from settle(probe)
    delay_written_s = probe.now_s
    delay_landed_s = yield Send(Delay(CONTROL_DELAY_S * 1000))
    delay_at = probe.wire.written_bytes
    delay_end_s = delay_landed_s + CONTROL_DELAY_S
    known.busy_until_s = delay_end_s
    pause_landed_s = yield Send(PauseToggle())
    pause_at = probe.wire.written_bytes
    yield from wait_until(probe, delay_end_s + READBACK_TIMEOUT_S, lambda: _paused_since(probe, pause_landed_s))
    paused = _paused_since(probe, pause_landed_s)
    default = DOCUMENTED["control_frames"]
    behind = f"behind a {CONTROL_DELAY_S:g} s delay that ends {delay_end_s - pause_landed_s:.2f} s after it landed"
    if paused is None:  # dropped (a FIFO of one frame) or ignored: nothing to resume
        known.busy_until_s = delay_end_s
        return Finding("control_frames", default, None,
                       f"a pause toggle written {behind} was never reported paused (kind 4)", UNSURE)
    confirmed_s = paused[1]
    lag = f"the pause was reported {paused[0] - pause_landed_s:.2f} s (confirmed {confirmed_s - pause_landed_s:.2f} s) after the toggle landed"
    # Judged by what the port's reports prove (a buffer may hold either frame): paused before the
    # delay could have ended → arrival; paused after it, and after the toggle surely landed by
    # more than an arrival's confirmation takes (two kind-4 frames, lost ones allowed) → queued.
    rotation_s = STATUS_PERIOD_S * len(STATUS_ROTATION)
    earliest_end_s = probe.earliest_landing(delay_at, delay_written_s) + CONTROL_DELAY_S
    toggle_by_s = probe.landed_by(pause_at, pause_landed_s)
    if confirmed_s < earliest_end_s - 2 * rotation_s / 3:
        finding = Finding("control_frames", default, "arrival", f"{lag}, {behind}: it acted on arrival", SURE)
    elif toggle_by_s is None or confirmed_s - toggle_by_s <= ARRIVAL_CONFIRM_ROTATIONS * rotation_s:
        shown = "after that" if toggle_by_s is None else f"{confirmed_s - toggle_by_s:.2f} s before it"
        finding = Finding("control_frames", default, None, f"{lag}, {behind}, but the port's reports show the toggle "
                          f"landed only {shown}: acting on arrival would look the same (a buffer held it?)", UNSURE)
    elif confirmed_s >= delay_end_s:
        finding = Finding("control_frames", default, "queued", f"{lag}, {behind}: it waited in the FIFO", SURE)
    else:
        finding = Finding("control_frames", default, None, f"{lag}, {behind}: too close to tell", UNSURE)
    # resume (in both modes it acts now: nothing else is queued)
    resume_landed_s = yield Send(PauseToggle())
    ok = yield from wait_until(probe, resume_landed_s + READBACK_TIMEOUT_S, lambda: _running_since(probe, resume_landed_s))
    if not ok:
        raise ProbeStop("the arm did not resume after the probe's pause toggle")
    if finding.value == "arrival":  # the delay was frozen while paused: it runs on from here
        known.busy_until_s = resume_landed_s + max(0.0, delay_end_s - pause_landed_s)
    _note(probe, "pause toggled and resumed (the arm is running, as found)")
    return finding


# --- restore ------------------------------------------------------------------------------------


def _last_change_s(probe, kinds) -> float:
    latest = float("-inf")
    for kind in kinds:
        previous = None
        for t, frame in probe.seen.by_kind.get(kind, [])[-40:]:
            if previous is not None and frame != previous:
                latest = max(latest, t)
            previous = frame
    return latest


def restore(probe):
    """Put back what the probe changed: pause state, pose (after a motion step), worktable origin,
    PWM — each read back.  Runs at the end and on Ctrl-C."""
    known = getattr(probe, "known", None)
    if known is None:
        return None
    yield from resume_if_paused(probe, probe.now_s - 1.0)
    # Let what is queued (delays, PWM-only frames, a small move) finish: quiet and past its planned end
    started_s = probe.now_s
    kinds = (PauseStatus.KIND, JointsLowStatus.KIND, JointsHighStatus.KIND)

    def busy_until_s() -> float:
        return max(known.busy_until_s, known.queued_until_s() if known.queued_until_s else 0.0)

    def quiet():
        return probe.now_s >= busy_until_s() and probe.now_s - _last_change_s(probe, kinds) >= QUIET_S

    def deadline_s() -> float:  # (it moves on while a FIFO round's fillers may still be running)
        return max(started_s, busy_until_s()) + QUIET_LIMIT_S

    while not quiet() and probe.now_s < deadline_s():
        limit_s = deadline_s()
        yield from wait_until(probe, limit_s, lambda: quiet() or deadline_s() > limit_s)
    known.busy_until_s, known.queued_until_s = busy_until_s(), None
    # judge by readings the arm built after the last frame landed and everything sent had ended
    since_s = max(probe.line_free_s, known.busy_until_s)
    yield from wait_until(probe, since_s + READBACK_TIMEOUT_S, lambda: _readings(probe, since_s) is not None)
    yield from resume_if_paused(probe, since_s)  # a pause toggle that was still queued has acted by now
    if known.moved:
        yield from return_to_start(probe)
    if not _origin_is(probe, since_s, known.origin_mm):
        yield from put_origin_back(probe)
    pwm = probe.seen.agreed(PauseStatus.KIND, since_s, pwm_of)
    if pwm is None or pwm[1] != known.pwm_us:
        yield from put_pwm_back(probe)
    yield from check_as_found(probe)
    return None


def return_to_start(probe):
    """After an interrupted move: a slow joint move back to the joints the arm started at."""
    known = probe.known
    joints = agreed_joints(probe, probe.now_s - 0.6)
    if joints is not None and max(abs(a - b) for a, b in zip(joints, known.joints_deg)) <= ARRIVED_DEG:
        return
    landed_s = yield Send(JointMove(*known.joints_deg, pwm_us=known.pwm_us, speed_deg_s=JOINT_SPEED_DEG_S))

    def back():
        now = agreed_joints(probe, landed_s)
        return now is not None and max(abs(a - b) for a, b in zip(now, known.joints_deg)) <= ARRIVED_DEG

    ok = yield from wait_until(probe, landed_s + 30.0, back)
    probe.notes.append("pose put back (joints as found)" if ok else "not restored: the arm did not report its start joints")


def check_as_found(probe):
    """Read the arm once more: say what is as the probe found it, and what is not."""
    since_s = probe.now_s
    yield Wait(since_s + READBACK_TIMEOUT_S, lambda: _readings(probe, since_s) is not None)
    known, now = probe.known, _readings(probe, since_s)
    if now is None:
        probe.notes.append("not checked: the arm's status did not show its state at the end")
        return
    same = {"worktable origin": _close(now["origin"], known.origin_mm, ORIGIN_TOLERANCE_MM),
            "PWM": now["pwm"] == known.pwm_us, "running (not paused)": not now["paused"],
            "joints": _close(now["joints"], known.joints_deg, STILL_TOLERANCE_DEG)}
    good = [name for name, ok in same.items() if ok]
    bad = [name for name, ok in same.items() if not ok]
    if good:
        probe.notes.append("as found: " + ", ".join(good))
    if bad:
        probe.notes.append("NOT as found: " + ", ".join(bad) + f" (now {now})")


def resume_if_paused(probe, since_s: float):
    state = probe.seen.agreed(PauseStatus.KIND, since_s, paused_of)
    if state is not None and state[1]:
        landed_s = yield Send(PauseToggle())
        ok = yield from wait_until(probe, landed_s + READBACK_TIMEOUT_S, lambda: _running_since(probe, landed_s))
        _note(probe, "pause state restored (running)" if ok else "not restored: the arm may still be paused")


def pwm_frame(probe, pwm_us: float) -> JointMove:
    """A PWM-only frame: a joint move to the joints the arm reported, so nothing but the PWM changes."""
    return JointMove(*probe.known.joints_deg, pwm_us=pwm_us, speed_deg_s=GRIPPER_SPEED_DEG_S)


def put_pwm_back(probe):
    known = probe.known
    landed_s = yield Send(pwm_frame(probe, known.pwm_us))

    def back():
        got = probe.seen.agreed(PauseStatus.KIND, landed_s, pwm_of)
        return got is not None and got[1] == known.pwm_us

    ok = yield from wait_until(probe, landed_s + QUIET_LIMIT_S / 4, back)
    _note(probe, f"PWM put back to {known.pwm_us} µs" if ok else f"not restored: PWM {known.pwm_us} µs was not reported back")
