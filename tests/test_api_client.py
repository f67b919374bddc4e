"""What ``armctl run`` needs from the Python API, used from Python: the observer, the journal
(``log=``) and ``resume=``, ``abort=``, ``toggle_pause``, ``feed_override(relative=True)``,
``stop(why)`` and a second stop, a stop before the first frame, and ``Arm.open(connect=)``.

All on the simulator with a virtual clock, in-process (model time moves only while the arm's
worker waits: every figure is the same on any machine).  The simulated arm's own record of the
frames it received is the witness of what was sent.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from armctl import Arm, ArmctlError, JobObserver
from armctl.errors import ResumeRefused
from armctl.core.protocol import PauseToggle, ResetConnector

SCRIPTS = Path(__file__).resolve().parent / "data" / "scripts_cli"
SHORT = SCRIPTS / "short_job.txt"  # 5 frames, under a second of arm time
TIMED = SCRIPTS / "timed_job.txt"  # a pick and place, about 30 s of arm time
VIRTUAL = "sim://?clock=virtual"


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)


def received(arm: Arm) -> list:
    return [frame.command for frame in arm._link.port.model.frames_received]


class Recorder(JobObserver):
    """Every call, in order; ``on_update(view)`` lets a test act from inside the job."""

    def __init__(self, on_update=None) -> None:
        self.calls: list[tuple] = []
        self.on_update = on_update

    def started(self, view, plan) -> None:
        self.calls.append(("started", view.total_frames, plan.from_line))

    def update(self, view) -> None:
        self.calls.append(("update", view.frames_sent, view.pause_state, view.feed_percent))
        if self.on_update is not None:
            self.on_update(view)

    def note(self, text: str) -> None:
        self.calls.append(("note", text))

    def warning(self, diagnostic) -> None:
        self.calls.append(("warning", diagnostic.code))

    def named(self, name: str) -> list[tuple]:
        return [call for call in self.calls if call[0] == name]


def test_the_observer_sees_the_start_every_turn_and_the_scripts_warnings(tmp_path):
    job = tmp_path / "job.txt"
    job.write_text(SHORT.read_text() + "G1 X220 Y10 Z280 A180 B0 C0 F6000 ; W: a line that does not move\n")
    watch = Recorder()
    with Arm.open(port=VIRTUAL) as arm:
        result = arm.run(job, observer=watch)
    assert result.finished
    assert watch.calls[0] == ("started", result.total_frames, 1)
    updates = watch.named("update")
    assert updates[-1][1] == result.frames_sent and [u[1] for u in updates] == sorted(u[1] for u in updates)
    assert watch.named("note") == []  # nothing to say about a job that ran through


def test_a_job_journalled_with_log_resumes_from_the_proven_line_every_line_once(tmp_path):
    log_path = tmp_path / "job.log"
    with Arm.open(port=VIRTUAL) as arm:
        def stop_early(progress):
            if progress.frames_sent == 3:
                arm.stop()

        with log_path.open("w", encoding="utf-8") as log:
            first = arm.run(TIMED, on_progress=stop_early, log=log)
        assert first.outcome == "interrupted" and first.resume_line is not None
        records = [json.loads(line) for line in log_path.read_text().splitlines()]
        assert records[0]["dir"] == "job" and any(r["dir"] == "progress" for r in records)
        watch = Recorder()
        rest = arm.run(TIMED, resume=log_path, observer=watch)
        assert rest.finished
        resumed_at = watch.named("started")[0][2]
        assert any(f"at line {resumed_at}" in call[1] for call in watch.named("note"))
        # the arm ran out its queue (resumed, then at rest at the last target written): the log
        # proves every line sent ran, so the job goes on after the last line sent — each frame once
        assert resumed_at > first.last_line_sent
        assert first.frames_sent + rest.frames_sent == first.total_frames


def test_resume_refuses_a_log_of_another_script_and_from_line_with_it(tmp_path):
    log_path = tmp_path / "job.log"
    with Arm.open(port=VIRTUAL) as arm:
        with log_path.open("w", encoding="utf-8") as log:
            arm.run(SHORT, log=log)
        before = len(received(arm))
        with pytest.raises(ResumeRefused, match="other contents"):
            arm.run(TIMED, resume=log_path)
        with pytest.raises(ResumeRefused, match="drop from_line"):
            arm.run(SHORT, resume=log_path, from_line=3)
        assert len(received(arm)) == before  # nothing sent


def test_abort_chooses_what_a_stop_sends():
    for abort, expected in (("pause", PauseToggle), ("reset-connector", ResetConnector)):
        with Arm.open(port=VIRTUAL) as arm:
            def stop_early(progress):
                if progress.frames_sent == 2:
                    arm.stop()

            result = arm.run(TIMED, on_progress=stop_early, abort=abort)
            assert result.outcome == "interrupted"
            assert isinstance(received(arm)[-1], expected), (abort, received(arm)[-3:])
    with Arm.open(port=VIRTUAL) as arm, pytest.raises(ValueError, match="abort="):
        arm.run(SHORT, abort="explode")


def test_toggle_pause_acts_on_the_job_only_and_feed_override_steps_relative():
    with Arm.open(port=VIRTUAL) as arm:
        with pytest.raises(ArmctlError, match="no job is running"):
            arm.toggle_pause()  # idle: nothing is sent to the arm
        with pytest.raises(ArmctlError, match="no job is running"):
            arm.feed_override(10, relative=True)
        assert received(arm) == []
        answers = []

        def act(view):
            if view.frames_sent == 2 and not answers:
                answers.append(arm.feed_override(-30, relative=True))
                answers.append(arm.feed_override(+10, relative=True))
                answers.append(arm.toggle_pause())  # pause
            elif view.pause_state == "paused" and len(answers) == 3:
                answers.append(arm.toggle_pause())  # a pause asked: this resumes it

        watch = Recorder(act)
        result = arm.run(TIMED, observer=watch)
    assert answers == [70, 80, True, True]
    assert result.finished
    assert any(call[3] == 80 for call in watch.named("update"))
    assert len([c for c in received(arm) if isinstance(c, PauseToggle)]) == 2  # the pause, the resume


def _recording_connect(written: list):
    from armctl.host.link import connect as real_connect

    def connect(port, baud, profile=None):
        link, baud = real_connect(port, baud, profile=profile)
        write = link.write
        link.write = lambda frame: (written.append(bytes(frame)), write(frame))[1]
        return link, baud

    return connect


def _updates_after_the_stop_note(cut: bool) -> tuple[str, int]:
    written: list[bytes] = []
    with Arm.open(port=VIRTUAL, connect=_recording_connect(written)) as arm:
        state = {"stopping": False, "after": 0}

        class Watch(JobObserver):
            def update(self, view) -> None:
                if view.frames_sent == 2 and not state["stopping"]:
                    arm.stop()
                    arm.stop()  # before the abort began: the same stop, the abort sequence still goes
                elif state["stopping"]:
                    state["after"] += 1
                    if cut and state["after"] == 1:
                        arm.stop()  # the abort is waiting for the arm: stop waiting

            def note(self, text: str) -> None:
                state["stopping"] = state["stopping"] or "sending the abort sequence" in text

        result = arm.run(TIMED, observer=Watch())
        assert written[-1] == PauseToggle().encode()  # the abort sequence went both times
        return result.outcome, state["after"]


def test_a_second_stop_cuts_the_wait_for_the_arm_short_but_never_the_abort_sequence():
    outcome, waited = _updates_after_the_stop_note(cut=False)
    cut_outcome, cut_waited = _updates_after_the_stop_note(cut=True)
    assert outcome == cut_outcome == "interrupted"
    assert waited > 2 and cut_waited <= 2  # without the cut the abort waits for rest, turn after turn


def test_a_stop_before_the_first_frame_sends_nothing():
    with Arm.open(port=VIRTUAL) as arm:
        arm.stop("stopped by a test")  # nothing running: does nothing, and a job asked later runs
        assert arm.run(SHORT).finished
        before = len(received(arm))
        real = arm._link.wait_until
        calls = []

        def stop_while_reading(*args, **kwargs):
            if not calls:
                calls.append(1)
                arm.stop()  # as Ctrl-C while the arm is read
            return real(*args, **kwargs)

        arm._link.wait_until = stop_while_reading
        result = arm.run(SHORT)
        arm._link.wait_until = real
        assert result.outcome == "interrupted" and result.frames_sent == 0 and result.exit_code == 130
        assert len(received(arm)) == before


def test_stop_why_goes_into_the_results_messages():
    with Arm.open(port=VIRTUAL) as arm:
        def stop_early(progress):
            if progress.frames_sent == 2:
                arm.stop("stopped by SIGTERM")

        result = arm.run(TIMED, on_progress=stop_early)
    assert result.outcome == "interrupted" and "stopped by SIGTERM" in result.messages


def test_open_takes_a_connect_seam_and_a_loaded_profile():
    from armctl.host.profile import load_profile

    written: list[bytes] = []
    with Arm.open(VIRTUAL, profile=load_profile(None), connect=_recording_connect(written)) as arm:
        result = arm.run(SHORT)
    assert result.finished and len(written) == result.frames_sent


@pytest.mark.realtime
def test_an_unprobed_arm_ends_finished_unproven_with_exit_1_in_the_api_and_in_armctl_run(tmp_path, sim_pty):
    """One fact in one place: ``armctl run``'s outcome and exit code are the ``RunResult``'s.
    A device path whose FIFO size was never probed (no armctl.toml) cannot prove a frame was
    not dropped: the API returns "finished, unproven" (not raised), exit_code 1; the CLI's
    --json summary is that result, and it exits with that code."""
    import subprocess
    import sys

    with Arm.open(port=sim_pty) as arm:
        api = arm.run(SHORT, timeout=10)
    assert (api.outcome, api.finished, api.exit_code) == ("finished, unproven", False, 1)
    done = subprocess.run([sys.executable, "-m", "armctl", "run", str(SHORT), "--port", sim_pty, "--json"],
                          capture_output=True, text=True, timeout=60, cwd=tmp_path)
    summary = json.loads(done.stdout.splitlines()[-1])
    assert summary["event"] == "summary"
    assert (summary["outcome"], summary["exit_code"], done.returncode) == (api.outcome, api.exit_code, 1), done.stderr
