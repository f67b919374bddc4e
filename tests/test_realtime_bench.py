"""The real-time benchmark's parts (issue 21): ``armctl sim --pty --stats`` reports what the arm
saw, and the bench's figures come from those records.  The whole table (about two minutes of wall
clock) is ``armctl bench --realtime``, not a test: speed goals are checked by benchmarks.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys

import pytest
from click.testing import CliRunner

from armctl.bench.realtime import _job_figures, abort_figures, moving_frames
from armctl.bench.scenarios import tiny_moves, true_durations_s
from armctl.ui.cli import main
from armctl.host.link import Link
from armctl.core.protocol import frame_seconds
from armctl.sim.model import SimOptions


@pytest.mark.realtime
@pytest.mark.timeout(30)
def test_sim_pty_writes_what_the_arm_saw_when_stopped(tmp_path):
    stats_path = tmp_path / "stats.json"
    process = subprocess.Popen([sys.executable, "-m", "armctl", "sim", "--pty", "--url",
                                "sim://?write_buffer_bytes=4096&read_granularity_ms=16", "--stats", str(stats_path)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        path = process.stdout.readline().split()[3]
        frames = [command.encode() for command in tiny_moves(3)]
        with Link.open(path, 9600) as link:
            for frame in frames:
                link.write(frame)
            assert link.wait_until(lambda state: state.complete, 5.0)
    finally:
        process.send_signal(signal.SIGINT)
        assert process.wait(10) == 130
    stats = json.loads(stats_path.read_text())
    assert stats["dropped"] == 0 and stats["complete"] and stats["clock_start_s"] > 0
    arrivals = [arrival for _, arrival, accepted in stats["frames"] if accepted]
    assert len(arrivals) == 3
    # written back to back: they land a frame time apart
    assert arrivals[2] - arrivals[1] == pytest.approx(frame_seconds(9600), abs=1e-6)


def test_stats_go_with_a_pty_only():
    result = CliRunner().invoke(main, ["sim", "--tcp", "5999", "--stats", "x.json"])
    assert result.exit_code == 2 and "--stats goes with --pty" in result.output


def test_bench_realtime_runs_its_own_jobs():
    result = CliRunner().invoke(main, ["bench", "--realtime", "--scenario", "tiny"])
    assert result.exit_code == 2 and "--realtime runs its own jobs" in result.output


def _stats(frames, executions, clock_start_s=100.0):
    return {"frames": frames, "executions": executions, "clock_start_s": clock_start_s, "time_scale": 1.0}


def test_the_figures_come_from_the_arms_records():
    commands = tiny_moves(4)
    f = frame_seconds(9600)
    frames = [[k, (k + 1) * f, True] for k in range(4)]
    executions = [[k, (k + 1) * f, (k + 1) * f + 0.01, "done"] for k in range(4)]
    mean_s, job_s, end_s = _job_figures(_stats(frames, executions), 4, 9600)
    assert mean_s == pytest.approx(f) and end_s == pytest.approx(4 * f + 0.01) and job_s == pytest.approx(end_s)
    # the abort written after 2 job frames, 1 ms after the second landed: it lands third, while the
    # arm is still in the second (60 ms long here); the arm moved until the second ended
    stopped_s = 100.0 + 2 * f + 0.001
    frames2 = frames[:2] + [[2, 3 * f, True]]
    executions2 = [executions[0], [1, 2 * f, 2 * f + 0.06, "done"]]
    durations = true_durations_s(commands, SimOptions())
    moving_s, bound_s = abort_figures(_stats(frames2, executions2), 2, stopped_s, 2.0, durations,
                                      moving_frames(commands, SimOptions()))
    assert moving_s == pytest.approx(0.06 - 0.001)
    assert bound_s == pytest.approx(durations[1] + max(2.0, durations[2]))  # in progress + max(lead, next)
