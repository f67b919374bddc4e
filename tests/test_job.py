"""The job engine (armctl/core/job.py) on its own: hand-fed status frames and ``now``, no port, no
simulator, no thread — every test runs in milliseconds of CPU whatever the model times.

A ``FakeArm`` stands for the arm: it runs each frame written for the motion model's time (it
reports the start of a move until the move ends, then its end), reports a full rotation of
position, joints and pause every ``STATUS_PERIOD_S``, and a pause toggle stops it where it is.
"""

from __future__ import annotations

import pytest

from armctl.core.job import (
    REST_CHECK_S, SETTLE_SLACK_S, Done, Job, Outcome, RunView, Wait, Write, agreed_pause,
)
from armctl.core.motion import MotionModel
from armctl.host.profile import load_profile
from armctl.core.protocol import (
    STATUS_PERIOD_S, JointsHighStatus, JointsLowStatus, PauseStatus, PauseToggle, PositionStatus,
)
from armctl.script import InitialState, compile_text
from armctl.core.streamer import Streamer

MODEL = MotionModel(load_profile())
START = MODEL.initial_pose()
X, Y, Z = START.xyz
THREE_MOVES = f"G1 X{X + 30:.1f} F600\nG1 Y{Y + 30:.1f}\nG1 X{X:.1f}\n"


def make_job(text: str = THREE_MOVES) -> Job:
    initial = InitialState(pose=tuple(START.cartesian), joints_deg=tuple(START.joints), pwm_us={1: START.pwm_us[0]})
    statements = list(compile_text(text, initial=initial))
    streamer = Streamer(MODEL, START)
    view = RunView(total_frames=len(statements), estimated_job_s=10.0, lead_s=streamer.lead_s,
                   capacity=streamer.limit_frames)
    return Job(streamer, statements, view)


class FakeArm:
    def __init__(self, job: Job, paused: bool = False, silent_after_s: float = float("inf")) -> None:
        self.job = job
        self.xyz = tuple(round(v, 1) for v in START.xyz)
        self.joints = tuple(round(v, 2) for v in START.joints)
        self.moves: list[tuple[float, float, tuple]] = []  # (start, end, target xyz)
        self.paused = paused
        self.frozen_at: float | None = None
        self.silent_after_s = silent_after_s
        self.next_status_s = 0.0
        self.written: list[Write] = []

    def wrote(self, action: Write, now: float) -> None:
        self.written.append(action)
        if action.statement is None:
            if action.frame == PauseToggle().encode():
                self.paused = not self.paused
                self.frozen_at = now
            return
        segment = self.job.streamer.pending[-1].segment
        begin = max([now] + [end for _, end, _ in self.moves])
        self.moves.append((begin, begin + segment.duration_s, tuple(segment.end.xyz)))

    def position(self, t: float) -> tuple:
        xyz = self.xyz
        for begin, end, target in self.moves:
            if self.frozen_at is not None and end > self.frozen_at:
                break
            if end <= t:
                xyz = target
        return tuple(round(v, 1) for v in xyz)

    def report(self, t: float) -> None:
        for frame in (PositionStatus(*self.position(t)), JointsLowStatus(*self.joints[:3]),
                      JointsHighStatus(*self.joints[3:]), PauseStatus(1 if self.paused else 0, 1500)):
            self.job.receive_status(frame, t)


def drive(job: Job, arm: FakeArm, stop_at_s: float | None = None, why: str | None = None,
          limit_s: float = 600.0) -> tuple[Done, float]:
    """The host loop, in virtual time: jump to the next status rotation or the engine's time."""
    now = 0.0
    while now < limit_s:
        if stop_at_s is not None and now >= stop_at_s and not job.stop_requested:
            job.request_stop(why)
        action = job.next_action(now)
        if isinstance(action, Done):
            return action, now
        if isinstance(action, Write):
            job.wrote(now)
            arm.wrote(action, now)
            continue
        assert isinstance(action, Wait)
        assert action.until_s is None or action.until_s > now, "a Wait for nothing: the host would spin"
        status_s = arm.next_status_s if arm.next_status_s < arm.silent_after_s else None
        candidates = [t for t in (status_s, action.until_s, stop_at_s if not job.stop_requested else None)
                      if t is not None]
        assert candidates, "a Wait with no status frame coming and no time would hang the host"
        now = max(now, min(candidates))
        if status_s is not None and now >= status_s:
            arm.report(now)
            arm.next_status_s = now + STATUS_PERIOD_S
    raise AssertionError(f"the job did not end within {limit_s} s")


def job_frames(arm: FakeArm) -> list[Write]:
    return [w for w in arm.written if w.statement is not None]


def test_a_job_finishes_when_the_arm_rests_at_its_last_target():
    job = make_job()
    arm = FakeArm(job)
    action, now = drive(job, arm)
    assert action == Done(Outcome.FINISHED) and job.view.outcome == "finished"
    assert len(job_frames(arm)) == 3
    motion_end_s = arm.moves[-1][1]
    # the arm time is the end of the last motion, as seen one status period late at most
    assert motion_end_s <= job.view.arm_done_s <= motion_end_s + STATUS_PERIOD_S
    assert now >= job.view.arm_done_s + REST_CHECK_S  # not called done before it rested
    assert job.streamer.all_consumed and job.view.resume_line() is None


def test_ctrl_c_mid_job_sends_the_abort_sequence_then_ends_interrupted():
    job = make_job()
    arm = FakeArm(job)
    action, _ = drive(job, arm, stop_at_s=1.0)
    assert action == Done(Outcome.INTERRUPTED)
    aborts = [w for w in arm.written if w.statement is None]
    assert aborts == [Write(PauseToggle().encode(), None)]
    assert arm.written[-1] == aborts[0]  # nothing of the job after it
    assert len(job_frames(arm)) < 3
    # the first move had not ended when the arm stopped: the resume line is the first line
    assert job.view.resume_line() == 1 and job.view.messages == []


def test_an_arm_already_paused_is_sent_no_pause_toggle():
    job = make_job()
    arm = FakeArm(job)
    arm.paused = True  # the arm reports it is paused (two agreeing reports before the stop)
    action, _ = drive(job, arm, stop_at_s=0.5)
    assert action == Done(Outcome.INTERRUPTED)
    assert [w for w in arm.written if w.statement is None] == []
    assert "already paused: no pause toggle sent" in job.view.messages[0]


def test_one_paused_report_is_not_believed():
    job = make_job()
    for paused, t in ((False, 0.0), (True, 0.03)):  # one flipped byte
        job.receive_status(PauseStatus(1 if paused else 0, 1500), t)
    assert job.arm_paused is None
    job.receive_status(PauseStatus(1, 1500), 0.06)
    assert job.arm_paused is True


@pytest.mark.parametrize("reports, agreed", [
    ((), None), ((True,), None), ((False, True), None), ((True, False), None),
    ((True, True), True), ((False, False), False), ((True, False, False), False),
])
def test_the_paused_twice_rule(reports, agreed):
    assert agreed_pause(reports) is agreed


def test_a_failure_stops_the_job_like_ctrl_c_and_ends_failed_with_its_reason():
    job = make_job()
    arm = FakeArm(job)
    action, _ = drive(job, arm, stop_at_s=1.0, why="the log job.log could not be written (disk full)")
    assert action == Done(Outcome.FAILED) and job.view.outcome == "failed"
    assert [w.frame for w in arm.written if w.statement is None] == [PauseToggle().encode()]
    assert job.view.messages == ["the log job.log could not be written (disk full)"]


def test_no_confirmation_when_the_status_frames_stop():
    job = make_job()
    arm = FakeArm(job, silent_after_s=0.0)  # not one status frame
    action, now = drive(job, arm)
    assert action == Done(Outcome.NO_CONFIRMATION)
    assert "did not confirm the end of the job in time" in job.view.messages[-1]
    assert job.view.arm_done_s is None
    # it waited for the estimate (× the slowest factor) and the slack, not longer
    estimate_s = job.streamer.estimated_finish_s()
    assert estimate_s + SETTLE_SLACK_S <= now <= 2 * estimate_s + SETTLE_SLACK_S + STATUS_PERIOD_S


def test_a_lost_port_ends_the_job_at_once():
    job = make_job()
    assert isinstance(job.next_action(0.0), Write)
    job.wrote(0.0)
    job.port_lost("the port went away")
    assert job.next_action(0.1) == Done(Outcome.PORT_LOST)
    assert job.view.outcome == "port lost" and job.view.messages == ["the port went away"]


def test_asking_again_without_news_gives_the_same_write():
    job = make_job()
    first = job.next_action(0.0)
    assert isinstance(first, Write) and job.next_action(0.0) is first
    job.wrote(0.0)
    assert job.view.frames_sent == 1 and job.view.last_sent is first.statement


def test_the_engine_imports_no_io():
    """armctl/core/job.py and the armctl modules it imports (transitively) name no clock, thread,
    port or terminal library: the engine is pure, whoever hosts it."""
    import ast
    from pathlib import Path

    package = Path(__file__).resolve().parent.parent / "armctl"
    forbidden = {"time", "threading", "serial", "click", "rich", "queue", "socket", "select", "signal"}
    seen, todo = set(), ["core.job"]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        path = package / name.replace(".", "/")
        is_package = path.is_dir()  # (a package: its __init__.py, its relative imports from inside it)
        tree = ast.parse((path / "__init__.py" if is_package else path.with_suffix(".py")).read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                roots = [alias.name.split(".")[0] for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:  # within armctl: follow it ("from . import status_frames" names the module)
                    base = name.split(".") if is_package else name.split(".")[:-1]
                    base = base[: len(base) - (node.level - 1)]
                    todo.extend([".".join(base + [node.module])] if node.module
                                else [".".join(base + [alias.name]) for alias in node.names])
                    continue
                roots = [node.module.split(".")[0]]
            else:
                continue
            assert not forbidden & set(roots), f"armctl/{name}.py imports {roots}"
    assert "core.protocol" in seen


# --- whatever the arm says: the engine ends, never spins, never writes the job after a stop ----

from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

READINGS = st.one_of(
    st.none(),  # the frame was lost
    st.tuples(st.floats(-300, 300), st.floats(-300, 300), st.floats(-300, 300)),  # a corrupted position
)


@settings(max_examples=60, deadline=None)
@given(
    moves=st.integers(1, 3),
    stop_at_s=st.one_of(st.none(), st.floats(0.0, 12.0)),
    why=st.one_of(st.none(), st.just("a failure")),
    silent_after_s=st.floats(0.0, 30.0),
    pauses=st.lists(st.booleans(), max_size=40),
    noise=st.lists(READINGS, max_size=40),
)
def test_the_engine_always_ends_and_never_spins(moves, stop_at_s, why, silent_after_s, pauses, noise):
    text = "".join(THREE_MOVES.splitlines(keepends=True)[:moves])
    job = make_job(text)
    arm = FakeArm(job, silent_after_s=silent_after_s)
    real_report, rounds = arm.report, iter(range(10**9))

    def report(t: float) -> None:  # the fake arm's truth, with lost, corrupted and paused reports mixed in
        k = next(rounds)
        arm.paused = pauses[k % len(pauses)] if pauses and k < 3 * len(pauses) else arm.paused
        reading = noise[k % len(noise)] if noise and k < 2 * len(noise) else ()
        if reading is None:
            return
        if reading:
            job.receive_status(PositionStatus(*(round(v, 1) for v in reading)), t)
        real_report(t)

    arm.report = report
    action, now = drive(job, arm, stop_at_s=stop_at_s, why=why, limit_s=2_000.0)  # drive asserts Wait > now
    assert action.outcome in set(Outcome) - {Outcome.RUNNING, Outcome.PORT_LOST}
    if job.stop_requested:
        stopped = next(i for i, w in enumerate(arm.written) if w.statement is None) if any(
            w.statement is None for w in arm.written) else len(arm.written)
        assert all(w.statement is None for w in arm.written[stopped:])
        assert action.outcome == (Outcome.FAILED if why else Outcome.INTERRUPTED)
    if action.outcome is Outcome.FINISHED:
        assert job.view.arm_done_s is not None and job.view.arm_done_s <= now


def test_a_port_lost_while_sending_the_abort_says_it_was_not_sent():
    from armctl.host.runner import JobRunner

    class LostPort:
        """A link whose port goes away at the first abort frame."""

        clock = staticmethod(lambda: 0.0)
        error = None

        def write(self, frame: bytes) -> None:
            if frame == PauseToggle().encode():
                from armctl.errors import PortError

                raise PortError("the port /dev/ttyUSB0 went away")
            runner.request_stop()  # Ctrl-C once a frame of the job is written (before it, nothing is aborted)

        def wait(self, until_s) -> None:
            pass

    job = make_job()
    runner = JobRunner(LostPort(), job.streamer, job.statements, job.view)
    with pytest.raises(KeyboardInterrupt):
        runner.run()
    runner.abort((PauseToggle(),))
    assert runner.view.outcome == "port lost"
    assert runner.view.messages == ["the abort sequence was NOT sent: the port /dev/ttyUSB0 went away"]


def test_frames_after_the_last_motion_are_done_only_when_even_a_slow_arm_has_run_them():
    # Three delays leave no trace: at rest at the last target proves nothing about them, and an
    # arm slower than the model (Hypothesis found one 1.4× slower) is still in the third when
    # the estimate runs out; "finished" waits until an arm slowest_factor× slower is done.
    job = make_job("G4 P300\nG4 P300\nG4 P300\n")
    arm = FakeArm(job)
    action, now = drive(job, arm)
    assert action == Done(Outcome.FINISHED)
    assert now >= 3 * 0.3 * job.streamer.slowest_factor
    assert job.view.arm_time_s == pytest.approx(0.9, abs=0.1)  # the arm time is still the model's


class _NewsArm(FakeArm):
    """A FakeArm that records which of its frames were news — fed one by one, or as a run
    (``receive_statuses``, fed again after each frame it names)."""

    def __init__(self, job: Job, as_run: bool) -> None:
        super().__init__(job)
        self.as_run = as_run
        self.news: list[bool] = []

    def report(self, t: float) -> None:
        frames = [PositionStatus(*self.position(t)), JointsLowStatus(*self.joints[:3]),
                  JointsHighStatus(*self.joints[3:]), PauseStatus(1 if self.paused else 0, 1500)]
        if not self.as_run:
            self.news += [self.job.receive_status(frame, t) for frame in frames]
            return
        while frames:
            k = self.job.receive_statuses(frames, [t] * len(frames))
            taken = len(frames) if k is None else k + 1
            self.news += [False] * (taken - 1) + [k is not None]
            frames = frames[taken:]


def test_a_run_of_frames_is_news_where_one_frame_at_a_time_is():
    """``receive_statuses`` names the first frame ``receive_status`` calls news and takes none
    after it: fed either way, the same answers frame by frame and the same job."""
    runs = []
    for as_run in (False, True):
        job = make_job()
        arm = _NewsArm(job, as_run)
        runs.append((drive(job, arm), arm.news, job.view.frames_sent, job.view.status_frames, job.view.arm_time_s))
    assert runs[0] == runs[1]
    assert 0 < sum(runs[0][1]) < len(runs[0][1])  # some frames were news, and some not
