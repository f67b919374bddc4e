"""``armctl bench`` and ``armctl run`` are one engine: the same job on the same simulator gives
the same arm time.

The harness (armctl/bench/harness.py) is started where ``run`` starts: ``run`` first reads the
arm (every status kind, then two more rotations: jobflow.read_arm) and plans from the pose
it reported, so the harness's arm is read the same way and the job compiled from the same
reported state.  Both then drive armctl/core/job.py against the same deterministic simulated arm, in
virtual time, so the frames go at the same model times and the engine sees the same status
frames: the arm times agree to the printed precision (0.1 s), not merely within a status
rotation — a host loop that ended the job by its own rules would not.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.bench.harness import run_job
from armctl.bench.strategies import StreamerStrategy
from armctl.ui.cli import main
from armctl.host.jobflow import READ_ROTATIONS  # read_arm: all nine kinds, then two more rotations
from armctl.host.link import plausible_state
from armctl.core.motion import MotionModel
from armctl.host.profile import load_profile
from armctl.core.protocol import StatusReader
from armctl.script import compile_text
from armctl.sim.model import SimulatedArm
from armctl.sim.protocol_sim import parse_sim_url
from armctl.core.streamer import DEFAULT_LEAD_S
from armctl.core.checked import start_from_state

URL = "sim://?clock=virtual"
SCRIPTS = Path(__file__).resolve().parent.parent / "scripts"
ARM_TIME = re.compile(r"^arm time: ([\d.]+) s", re.M)


def bench_arm_time_s(text: str) -> float:
    options = parse_sim_url(URL)
    arm = SimulatedArm(options)
    profile = load_profile()
    model = MotionModel(profile)
    state, reader, frames, complete_at = plausible_state(profile), StatusReader(), 0, None
    while complete_at is None or frames < complete_at + 9 * READ_ROTATIONS:
        now = arm.next_output_time()
        for frame in reader.feed(arm.advance(now)):
            state.update(frame, now)
            frames += 1
        if complete_at is None and state.complete:
            complete_at = frames
    start, initial = start_from_state(model, state)
    commands = [statement.command for statement in compile_text(text, initial=initial)]
    result = run_job(commands, StreamerStrategy(model, start, DEFAULT_LEAD_S, options.baud), arm)
    assert result.outcome == "finished", result
    return result.arm_time_s


def run_arm_time_s(stdout: str) -> float:
    match = ARM_TIME.search(stdout)
    assert match, stdout
    return float(match.group(1))


@pytest.mark.parametrize("name", ["draw_square_circle.txt", "pick_and_place.txt"])
def test_bench_and_run_give_the_same_arm_time(name):
    script = SCRIPTS / name
    result = CliRunner().invoke(main, ["run", str(script), "--no-live", "--port", URL], env={"ARMCTL_PORT": None})
    assert result.exit_code == 0, result.output
    assert f"{bench_arm_time_s(script.read_text()):.1f}" == f"{run_arm_time_s(result.stdout):.1f}"


def test_bench_and_the_installed_run_give_the_same_arm_time(tmp_path):
    script = SCRIPTS / "joint_routine.txt"
    env_free = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path)}
    done = subprocess.run([sys.executable, "-m", "armctl", "run", str(script), "--no-live", "--port", URL],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path, env=env_free)
    assert done.returncode == 0, done.stderr
    assert f"{bench_arm_time_s(script.read_text()):.1f}" == f"{run_arm_time_s(done.stdout):.1f}"
