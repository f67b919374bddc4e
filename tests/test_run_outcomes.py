"""How a run ends, told truthfully: "done" only when the arm is at rest at the job's last target
and not paused; a pause toggle never sent to an arm that is already paused; a resume line the
compiler accepts (never inside an arc or a repeat block); a failed abort reported as one.

These run the real `armctl run` against `sim://?clock=virtual`, or the runner's pieces alone.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.core.estimate import JobEstimator
from armctl.host.link import config_baud, plausible_state
from armctl.core.motion import MotionModel
from armctl.host.profile import load_profile
from armctl.core.protocol import Delay
from armctl.host.jobflow import outermost_block_start

START = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F6000\n"


def run(tmp_path: Path, script: str, *args: str):
    path = tmp_path / "job.txt"
    path.write_text(script)
    return CliRunner().invoke(main, ["run", str(path), "--no-live", *args], env={"ARMCTL_PORT": None})


def test_a_job_whose_last_frames_were_cleared_is_not_reported_done(tmp_path):
    # RESET CONNECTOR (H5: acted on when it reaches the head) clears the frames queued behind it;
    # with a long lead they are already there. The arm stops short of the job's last target.
    script = START + "G1 Y120\nRESET CONNECTOR\nG1 Y-120\nG1 Z100\nG1 Z150\n"
    result = run(tmp_path, script, "--port", "sim://?clock=virtual", "--lead", "60")
    assert result.exit_code == 1, result.output
    assert "finished: the arm finished the job" not in result.stdout
    assert "but the job's last target is (250.0, -120.0, 150.0)" in result.stderr


def test_a_job_whose_frames_were_dropped_is_not_reported_done(tmp_path):
    # A 3-frame FIFO and a lead that lets the host outrun it: frames are dropped on the way.
    script = START + "".join(f"G1 Y{y}\n" for y in (60, -60, 60, -60, 0)) + "G1 Z100\n"
    result = run(tmp_path, script, "--port", "sim://?clock=virtual&fifo=3", "--lead", "60")
    assert result.exit_code == 1, result.output
    assert "finished: the arm finished the job" not in result.stdout


def test_a_finished_job_is_reported_done_with_the_arm_time(tmp_path):
    result = run(tmp_path, START + "G1 Y50\nG4 P300\n", "--port", "sim://?clock=virtual")
    assert result.exit_code == 0, result.output
    assert "finished: the arm finished the job" in result.stdout
    assert "arm time:" in result.stdout


def test_resume_inside_a_repeat_block_names_the_outermost_block_start(tmp_path):
    script = tmp_path / "loops.txt"
    script.write_text(
        "G4 P1\n"  # 1
        "O<rows> repeat [2]\n"  # 2
        "  O<cols> repeat [3]\n"  # 3
        "    G4 P1\n"  # 4
        "  O<cols> endrepeat\n"  # 5
        "O<rows> endrepeat\n"  # 6
        "G4 P1\n"  # 7
        "o100 REPEAT [1]\n"  # 8: numbered label, any case
        "G4 P1\n"  # 9
        "o100 endrepeat\n"  # 10
    )
    assert outermost_block_start(script.read_text().splitlines(), 4) == 2
    assert outermost_block_start(script.read_text().splitlines(), 5) == 2
    assert outermost_block_start(script.read_text().splitlines(), 1) is None
    assert outermost_block_start(script.read_text().splitlines(), 7) is None
    assert outermost_block_start(script.read_text().splitlines(), 9) == 8
    from armctl.script import compile_file

    assert compile_file(script, from_line=2).finish() == []  # the line it names is one run accepts


def test_the_summary_of_a_job_stopped_in_a_repeat_block_says_the_passes_done_run_again(capsys):
    """The text summary reads the job's RunResult (the --json summary) and adds the note."""
    from types import SimpleNamespace

    from armctl.host.api import RunResult
    from armctl.ui import run_job

    result = RunResult("interrupted", 3, 9, 4, 4, None, 2.0, 2, "armctl run loops.txt --from-line 2", ("stopped",), 130)
    view = SimpleNamespace(arm_time_s=None, first_not_done=SimpleNamespace(loop=(0, 1)), resume_line=lambda: 4)
    options = SimpleNamespace(abort="pause")
    assert run_job._summary(result, view, 1.0, SimpleNamespace(job_s=2.0), options) == 130
    out = capsys.readouterr()
    assert "frames: 3 of 9 sent" in out.out and "last line known executed: 4" in out.out
    assert ("resume with: armctl run loops.txt --from-line 2 (line 4 is inside a repeat block, in pass 2: "
            "the block runs again from its first pass") in out.out
    assert "note: stopped" in out.err and "stopped: interrupted; abort sequence: pause" in out.err


def test_the_estimate_never_queues_more_frames_than_the_streamer_would():
    profile = load_profile()
    model = MotionModel(profile)
    estimator = JobEstimator(model, model.initial_pose(), lead_s=600)
    for _ in range(600):
        estimator.add(Delay(500))
    assert estimator.result.peak_queue_frames <= estimator.frame_limit


def test_the_state_links_use_judges_jumps_against_the_profile():
    state = plausible_state(load_profile())
    assert state.max_speed_mm_s > 0 and state.max_joint_speed_deg_s > 0


@pytest.mark.parametrize("value", ["fast", 1.5, True, [9600], 10**9, 100])
def test_a_bad_baud_in_armctl_toml_is_a_clear_error(value):
    from armctl.errors import ConfigError

    with pytest.raises(ConfigError, match=r"armctl.toml: baud = .* must be a whole number of bit/s from 3000"):
        config_baud({"baud": value}, "armctl.toml")
    assert config_baud({}, "armctl.toml") == 9600


def test_ctrl_c_sends_no_pause_toggle_to_an_arm_that_is_already_paused(tmp_path, monkeypatch):
    # The script pauses the arm itself (control frames act on arrival), then Ctrl-C comes (the job
    # holds what follows a script's PAUSE: two frames sent): a pause toggle now would resume the
    # arm, so the abort must not send one.
    from armctl.ui import run_job

    real_update = run_job._Display.update
    pressed = []

    def update(self, view):
        real_update(self, view)
        if view.frames_sent == 2 and not pressed:
            pressed.append(True)
            raise KeyboardInterrupt

    monkeypatch.setattr(run_job._Display, "update", update)
    log = tmp_path / "log.jsonl"
    script = START + "PAUSE\nG1 Y100\n"
    result = run(tmp_path, script, "--port", "sim://?clock=virtual&control=arrival", "--log", str(log))
    assert result.exit_code == 130, result.output
    sent = [json.loads(line) for line in log.read_text().splitlines() if '"tx"' in line]
    pause_frames = [r for r in sent if r["hex"].startswith("fc1e0302")]
    assert len(pause_frames) == 1  # the script's own PAUSE, no abort toggle after it
    assert re.search(r"(already paused|PAUSE at line 2 was already written): no pause toggle sent", result.stderr)


# --- every example job, end to end in virtual time: done, and the arm time agrees with estimate ---

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "scripts").glob("*.txt"))
ARM_TIME = r"^arm time: ([\d.]+) s from the first frame to the arm at rest; estimated ([\d.]+) s"


@pytest.mark.parametrize("script", [p for p in EXAMPLES if p.name != "sd_program.txt"], ids=lambda p: p.name)
def test_every_example_finishes_within_5_percent_of_its_estimate(script):

    result = CliRunner().invoke(main, ["run", str(script), "--no-live", "--port", "sim://?clock=virtual"],
                                env={"ARMCTL_PORT": None})
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
    measured, estimated = map(float, re.search(ARM_TIME, result.stdout, re.M).groups())
    assert abs(measured / estimated - 1) <= 0.05, (measured, estimated)


def test_trailing_frames_that_move_nothing_count_in_the_arm_time(tmp_path):
    # PWM-only moves, a delay and a move to where the arm already is: 3 s after the last motion.
    script = START + "G1 Y50\nG1 S2000\nG1 S1000\nG4 P2000\nG1 Y50\n"
    result = run(tmp_path, script, "--port", "sim://?clock=virtual")
    assert result.exit_code == 0, result.output

    measured, estimated = map(float, re.search(ARM_TIME, result.stdout, re.M).groups())
    assert estimated > 2.0 and abs(measured / estimated - 1) <= 0.05, (measured, estimated)


def test_an_sd_program_longer_than_the_estimate_is_waited_for_and_reported(tmp_path):
    # The estimate cannot know how long PROGRAM 1 runs (the simulator: 4 s without moving the
    # arm, its run position advancing); run waits while the arm works, then confirms the end.
    sd = Path(__file__).resolve().parent.parent / "scripts" / "sd_program.txt"
    result = CliRunner().invoke(main, ["run", str(sd), "--no-live", "--port", "sim://?clock=virtual"],
                                env={"ARMCTL_PORT": None})
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
    assert "armctl waited until it stopped" in result.stderr
    estimate = CliRunner().invoke(main, ["estimate", str(sd)])
    assert "the SD program's own run time is unknown to armctl and not included" in estimate.stdout


def test_jitter_in_the_readings_is_not_taken_for_motion():
    from armctl.core.job import _moved_clearly

    here = ((200.0, 0.0, 150.0), (0.0, 10.0, 20.0), (0.0, 90.0, 0.0))
    assert not _moved_clearly(here, ((200.3, -0.2, 150.1), (0.1, 10.0, 19.9), (0.0, 90.1, 0.0)))
    assert _moved_clearly(here, ((201.0, 0.0, 150.0), here[1], here[2]))
    assert _moved_clearly(here, (here[0], here[1], (0.0, 90.0, 0.5)))
    assert _moved_clearly((None, here[1], here[2]), here)


def test_a_job_ending_in_an_sd_program_is_done_only_when_the_program_stops_advancing(tmp_path):
    # The simulated PROGRAM 1 holds a standing arm for 4 s: "at rest at the last target" alone
    # would call the job done while the program still runs.
    result = run(tmp_path, "POSE 1\nPROGRAM 1\n", "--port", "sim://?clock=virtual")
    assert result.exit_code == 0, result.output
    measured = float(re.search(ARM_TIME, result.stdout, re.M).group(1))
    assert 4.0 <= measured <= 5.5, result.stdout


@pytest.mark.parametrize("opening, closing", [("N10O<a> repeat [3]", "O<a> endrepeat"),  # an N number written close
                                              ("O<a> (three rows) repeat [3]", "O<a> (done) endrepeat")])
def test_a_stopped_job_resumes_at_the_repeat_line_however_the_grammar_lets_it_be_written(opening, closing):
    # The compiler reads "N10O<a> repeat" and "O<a> (comment) repeat" as repeat lines, so the
    # resume line must move out of the block for them too (one rule for what a repeat line is:
    # lint/scan.py's, which follows the grammar): a line inside the block cannot start a job.
    from armctl import Arm, ArmTimeout
    script = START + f"{opening}\nG1 Y50 F600\nG1 Y-50\n{closing}\nG1 Z100\n"
    with Arm.open("sim://?clock=virtual") as arm:
        with pytest.raises(ArmTimeout) as stopped:
            arm.run(script, timeout=12)
    assert stopped.value.result.resume_line == 2
