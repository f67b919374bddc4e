"""An SD program (PROGRAM n) on an arm whose control frames act as they land (H5 "arrival").

Found by a review: with ``[connector] control_frames = "arrival"`` and the simulator acting so,
scripts/sd_program.txt (POSE 0, POSE 1, PROGRAM 1, POSE 0, POSE 3) ended ``finished``, exit 0,
while its second POSE 0 had cut PROGRAM 1 short 0.27 s in: the motion model gives a program no
time (the host cannot see inside it), so the time bound confirmed the PROGRAM frame at once and
rule (c) let the next control frame go.  Now time never confirms a PROGRAM on such an arm: the
arm's reports do — it worked after the frame landed (its run position advanced, or it moved)
and rests since — and the control frame after it waits for that.  An arm whose reports never
show the program at work holds the job no longer than the engine waits for an SD program at
the end of a job (``JobEnd.overrun_limit_s``); the job then goes on and ends ``finished,
unproven``, saying which PROGRAM no report showed running.

Found next: on the document's arm (control frames queue) a long program held the FIFO while
time took it for 0 s, and the host wrote on into a full FIFO.  So time never confirms a PROGRAM
on any arm (armctl/core/job_program.py).

Judged by the simulator's own record (armctl/sim/program.py: a program holds the arm for
``PROGRAM_RUN_S`` without moving it, its run position advancing), in this process and through
the installed command in a fresh one, for both control-frame modes.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

import armctl.sim.program
from armctl.core.protocol import GoToPose, RunProgram
from armctl.sim.executor import DONE
from armctl.sim.program import PROGRAM_RUN_S
from armctl.ui.cli import main
from test_resume_exactly_once import _open_one_arm

pytestmark = pytest.mark.timeout(60)

JOB = Path(__file__).resolve().parents[1] / "scripts" / "sd_program.txt"
ARMCTL = Path(sys.executable).with_name("armctl")  # the installed command
MODES = ("queued", "arrival")


def _url(mode: str) -> str:
    return f"sim://?clock=virtual&control_frames={mode}"


def _profile_says(mode: str, where: Path) -> None:
    """The arm's control-frame mode, as a project armctl.toml states it (measured, not the guess)."""
    (where / "armctl.toml").write_text(f'[connector]\ncontrol_frames = "{mode}"\n')


def _run_here(mode: str, script: Path, tmp_path: Path, monkeypatch):
    """``armctl run`` in this process on the simulated arm: (the result, the arm's execution log)."""
    _profile_says(mode, tmp_path)
    monkeypatch.chdir(tmp_path)
    ports = _open_one_arm(monkeypatch)
    result = CliRunner().invoke(main, ["run", str(script), "--no-live", "--port", _url(mode)],
                                env={"ARMCTL_PORT": None})
    return result, ports[_url(mode)].model.execution_log


@pytest.mark.parametrize("mode", MODES)
def test_the_frames_after_a_program_wait_for_it_to_end(mode, tmp_path, monkeypatch):
    result, log = _run_here(mode, JOB, tmp_path, monkeypatch)
    (program,) = [e for e in log if isinstance(e.command, RunProgram)]
    # the arm ran the program to its end: no control frame after it cut it short
    assert program.outcome == DONE and program.duration_s >= PROGRAM_RUN_S - 1e-9, (program, result.output)
    assert [e.outcome for e in log] == [DONE] * 5, log
    poses_after = [e for e in log if isinstance(e.command, GoToPose) and e.start_s >= program.end_s]
    assert [e.command.pose for e in poses_after] == [0, 3]
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"


@pytest.mark.parametrize("mode", MODES)
def test_through_the_installed_command(mode, tmp_path):
    _profile_says(mode, tmp_path)
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    log = tmp_path / "run.jsonl"
    done = subprocess.run([str(ARMCTL), "run", str(JOB), "--json", "--port", _url(mode), "--log", str(log)],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=50)
    summary = json.loads(done.stdout.splitlines()[-1])
    assert (summary["outcome"], done.returncode) == ("finished", 0), done.stdout + done.stderr
    # the arm's time covers the whole program (4 s of it), not a program cut short
    assert summary["arm_time_s"] >= PROGRAM_RUN_S, summary
    # and the arm's own reports say so: the SD file status (kind 102, the simulator's 2 = finished,
    # 3 = stopped) never reads "stopped"
    decoded = subprocess.run([str(ARMCTL), "decode", "--json", str(log)], cwd=tmp_path, env=env,
                             capture_output=True, text=True, timeout=50)
    statuses = [json.loads(line) for line in decoded.stdout.splitlines()]
    file_status = [d["fields"]["raw"] for d in statuses if d.get("kind") == 102]
    assert 2 in file_status and 3 not in file_status, file_status


def test_a_program_no_report_shows_holds_the_job_only_a_bounded_time(tmp_path, monkeypatch):
    # An arm whose reports never show its program at work (the run position stays where it was,
    # the arm does not move): the job must not wait for ever, nor claim what no report proved.
    monkeypatch.setattr(armctl.sim.program.SdProgram, "position_at", lambda self, now_s: 0.0)
    result, log = _run_here("arrival", JOB, tmp_path, monkeypatch)
    (program,) = [e for e in log if isinstance(e.command, RunProgram)]
    assert program.outcome == DONE, program  # (waited for longer than the program's 4 s)
    assert [e.outcome for e in log] == [DONE] * 5, log
    assert result.exit_code == 1, result.output
    assert result.stdout.splitlines()[-1].startswith("finished, unproven"), result.stdout
    assert "no report showed PROGRAM 1 at frame 3 (line 13) running" in result.output, result.output


def test_a_queued_arm_runs_the_job_as_before(tmp_path, monkeypatch):
    # On the document's arm the frames behind the PROGRAM wait in the FIFO: a job that cannot
    # fill it runs as it did (arm time 6.4 s), time confirming nothing it did not before
    result, log = _run_here("queued", JOB, tmp_path, monkeypatch)
    assert result.exit_code == 0, result.output
    assert "arm time: 6.4 s" in result.stdout, result.stdout


def test_a_program_shorter_than_a_status_rotation_is_seen_by_its_run_position(tmp_path, monkeypatch):
    # 50 ms: over before a second report of any kind; its run position, changed, still shows it ran
    monkeypatch.setattr(armctl.sim.program, "PROGRAM_RUN_S", 0.05)
    result, log = _run_here("arrival", JOB, tmp_path, monkeypatch)
    assert [e.outcome for e in log] == [DONE] * 5, log
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
    assert float(result.stdout.split("arm time: ")[1].split(" s")[0]) < 10.0, result.stdout  # no long wait


def test_a_program_still_working_past_the_limit_ends_the_job_without_cutting_it_short(tmp_path, monkeypatch):
    # 300 s of visible work: past twice the 60 s an SD program is waited for, the job ends "no
    # confirmation" and sends nothing more (on this arm the next POSE would cut the program short)
    monkeypatch.setattr(armctl.sim.program, "PROGRAM_RUN_S", 300.0)
    result, log = _run_here("arrival", JOB, tmp_path, monkeypatch)
    assert [type(e.command) for e in log] == [GoToPose, GoToPose, RunProgram], log
    assert log[-1].outcome != "interrupted", log
    assert result.exit_code == 1, result.output
    assert "no confirmation" in result.output and "PROGRAM 1 at frame 3 (line 13) did not end in the 120 s" in result.output
    assert "last line known executed: 12" in result.stdout, result.stdout


def test_work_is_judged_on_values_agreed_after_the_frame_landed():
    # The kinds come in turn, a rotation (270 ms) apart: a joints report read just after a PROGRAM
    # landed may show the end of the move before it, which a reading taken before did not.  That
    # proves no work; nor do corrupted reports, which never agree (two reports in a row on one value).
    # A value agreed anew proves work after the arm was last read at the one agreed before.
    from armctl.core.job_readings import Readings, Written

    readings = Readings(Written())
    here, there = (0.0, 10.0, 20.0), (0.0, 30.0, 20.0)
    readings.take(1, here, 0.73)
    readings.take(1, here, 1.00)  # joints 1-3 at rest before the move, agreed
    readings.take(1, there, 1.27)  # the move's end, first read after the PROGRAM landed (at 1.10)
    readings.take(1, there, 1.54)
    assert not readings.worked_after(1.10)  # agreed anew, but on a value first read before the landing
    readings.take(1, (0.0, 90.0, 20.0), 1.81)  # two corrupted reports in a row ...
    readings.take(1, (0.0, 30.0, 99.0), 2.08)
    readings.take(1, there, 2.35)  # ... then where it was
    readings.take(1, there, 2.62)
    assert not readings.worked_after(1.10)
    readings.take(1, here, 2.89)
    assert not readings.worked_after(1.10)  # moved, not yet agreed
    readings.take(1, here, 3.16)
    assert readings.worked_after(2.62) and not readings.worked_after(2.63)  # from ``there``, last read at 2.62
    readings.take_run_position(0.0, 4.0)
    readings.take_run_position(0.0, 4.27)  # agreed before the next PROGRAM lands (at 4.3)
    readings.take_run_position(110.0, 4.54)  # only a program moves it: advancing ...
    readings.take_run_position(220.0, 4.81)
    assert not readings.worked_after(4.3)
    readings.take_run_position(220.0, 5.08)  # ... and stopped, agreed
    assert readings.worked_after(4.3) and readings.worked_after(4.81) and not readings.worked_after(4.82)


def test_a_users_pause_during_the_program_does_not_count_towards_its_wait():
    # Paused 90 s mid-program (longer than the 60 s an SD program is waited for), then resumed:
    # the program finishes, and only then does the POSE after it go.
    from armctl.core.job import Job, Outcome, RunView
    from armctl.core.motion import MotionModel
    from armctl.core.streamer import Streamer
    from armctl.host.profile import default_profile, with_connector
    from armctl.script import InitialState, compile_text
    from armctl.sim.model import SimOptions, SimulatedArm
    from test_job_pause import drive

    profile = with_connector(default_profile(), {"control_frames": "arrival"}, "the test")
    model = MotionModel(profile)
    start = model.initial_pose()
    initial = InitialState(pose=tuple(start.cartesian), joints_deg=tuple(start.joints), pwm_us={1: start.pwm_us[0]})
    statements = list(compile_text("POSE 1\nPROGRAM 1\nPOSE 0\n", initial=initial))
    streamer = Streamer(model, start)
    view = RunView(total_frames=3, estimated_job_s=3.0, lead_s=streamer.lead_s, capacity=streamer.limit_frames)
    job = Job(streamer, statements, view, control_frames="arrival")
    arm = SimulatedArm(SimOptions(profile=profile, control_frames="arrival"))
    log = arm.execution_log

    def pause(job, now):
        (program,) = [e for e in log if isinstance(e.command, RunProgram)]  # running since it landed
        assert now - program.start_s < PROGRAM_RUN_S
        assert job.pause()

    outcome, _, _ = drive(job, arm, at=[(3.0, pause), (93.0, lambda job, now: job.resume())])
    assert outcome == Outcome.FINISHED, view.messages
    program = [e for e in log if isinstance(e.command, RunProgram)][0]
    assert program.outcome == DONE and program.duration_s >= PROGRAM_RUN_S + 89.0, program
    (pose_after,) = [e for e in log if isinstance(e.command, GoToPose) and e.start_s >= program.end_s]
    assert pose_after.outcome == DONE and pose_after.command.pose == 0


FAULTS = "&noise=0.05&loss=0.05&corrupt=0.05&seed={seed}"


@pytest.mark.parametrize("seed", [1, 3, 5])
def test_lost_and_corrupted_reports_neither_cut_the_program_short_nor_prove_an_unseen_one(seed, tmp_path,
                                                                                          monkeypatch):
    def run(tag):
        where = tmp_path / tag
        where.mkdir()
        _profile_says("arrival", where)
        monkeypatch.chdir(where)
        url = _url("arrival") + FAULTS.format(seed=seed) + f"&fifo_frames={200 + len(tag)}"  # a fresh arm each run
        ports = _open_one_arm(monkeypatch)
        result = CliRunner().invoke(main, ["run", str(JOB), "--no-live", "--port", url], env={"ARMCTL_PORT": None})
        return result, ports[url].model.execution_log

    result, log = run("seen")
    assert [e.outcome for e in log] == [DONE] * 5, (log, result.output)
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job", result.output
    # a program no report shows: one corrupted report is no sign of its work
    monkeypatch.setattr(armctl.sim.program.SdProgram, "position_at", lambda self, now_s: 0.0)
    result, log = run("unseen")
    assert [e.outcome for e in log] == [DONE] * 5, (log, result.output)
    assert "no report showed PROGRAM 1 at frame 3 (line 13) running" in result.output, result.output


@pytest.mark.parametrize("reports", ["run position", "motion only"])
def test_a_program_that_moves_the_arm_is_waited_for_and_so_is_the_move_after_it(reports, tmp_path, monkeypatch):
    # An SD program that takes the arm to fixed pose 2 (the simulator's own programs stand still):
    # the POSE 0 after it starts there, not where the plan left the arm (pose 1), so its time is
    # not the plan's either, and the POSE 3 after it must not cut it short.
    import armctl.sim.executor

    def start_program(self, frame, now_s):
        segment = self.motion.plan(GoToPose(2), self._start_pose())
        self.program.start(frame.command.program, now_s, segment.duration_s / PROGRAM_RUN_S)  # as long as its move
        self._run(segment, [frame], now_s)

    monkeypatch.setattr(armctl.sim.executor.Executor, "_start_program", start_program)
    if reports == "motion only":
        monkeypatch.setattr(armctl.sim.program.SdProgram, "position_at", lambda self, now_s: 0.0)
    result, log = _run_here("arrival", JOB, tmp_path, monkeypatch)
    assert [e.outcome for e in log] == [DONE] * 5, (log, result.output)
    if reports == "run position":
        assert result.stdout.splitlines()[-1] == "finished: the arm finished the job", result.output


@pytest.mark.parametrize("mode", MODES)
def test_a_long_program_never_lets_the_fifo_overflow(mode, tmp_path, monkeypatch):
    # Found on the document's arm (H5: control frames queue): a 30 s SD program, then 400 short moves.
    # The program holds the FIFO; time said it took the model's 0 s, so the host counted the
    # moves behind it done and wrote on: 201 frames dropped, "last line known executed: 405" of 404 frames.
    # Now time never confirms a PROGRAM on any arm: the FIFO bound holds the host until the
    # arm's reports show the moves after it running.
    monkeypatch.setattr(armctl.sim.program, "PROGRAM_RUN_S", 30.0)
    script = tmp_path / "program_then_moves.txt"
    script.write_text("\n".join(["POSE 0", "POSE 1", "PROGRAM 1", "G90", "G1 X250 Y-50 Z150 A180 B0 C0 F3000 S1000"]
                                + [f"G1 Y{-49 if k % 2 == 0 else -50} F3000" for k in range(400)]) + "\n")
    _profile_says(mode, tmp_path)
    monkeypatch.chdir(tmp_path)
    ports = _open_one_arm(monkeypatch)
    result = CliRunner().invoke(main, ["run", str(script), "--no-live", "--port", _url(mode)],
                                env={"ARMCTL_PORT": None})
    arm = ports[_url(mode)].model
    assert arm.frames_dropped == 0, result.output
    assert [e.outcome for e in arm.execution_log] == [DONE] * 404
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
    # the arm time ran far over the estimate, which cannot know the program's 30 s: no note blames
    # an unmeasured speed_tolerance for it
    assert "may have slowed" not in result.output, result.output
