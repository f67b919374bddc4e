"""An arm whose connector holds fewer than 8 frames.  The profile refused any ``fifo_frames``
under 8, yet ``armctl probe`` kept what it measured (4 on ``sim://?fifo=4``) for every command
on the arm: every later command there — the probe itself included — exited 2 until the record
was forgotten.  And the streamer's 4-frame margin would have left such a connector nothing to
stream with; with 1 frame, a job with an arc never ended (its second frame waited for room the
first kept).  Now the streamer keeps half of a small connector free and writes at least 2 ahead
(``streamer.limit_frames``, the estimate's bound too), the profile takes 3 frames up, and the
probe keeps no value the profile refuses — it says so instead."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from click.testing import CliRunner

from armctl.core.streamer import CAPACITY_MARGIN_FRAMES, limit_frames
from armctl.ui.cli import main
from test_resume_exactly_once import _open_one_arm

pytestmark = pytest.mark.timeout(60)


def test_the_bound_keeps_the_margin_where_it_can_and_two_frames_always():
    assert [limit_frames(c) for c in (3, 4, 5, 6, 7, 8, 9, 200)] == [2, 2, 3, 3, 4, 4, 5, 200 - CAPACITY_MARGIN_FRAMES]


@pytest.mark.parametrize("fifo_frames", [3, 4, 5, 7])
@pytest.mark.parametrize("script", ["draw_square_circle", "pick_and_place"])
def test_a_small_connector_runs_every_frame_with_none_dropped(tmp_path, monkeypatch, fifo_frames, script):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "armctl.toml").write_text(f"[connector]\nfifo_frames = {fifo_frames}\n")
    ports = _open_one_arm(monkeypatch)
    url = f"sim://?clock=virtual&fifo_frames={fifo_frames}"
    path = os.path.join(os.path.dirname(__file__), "..", "scripts", f"{script}.txt")
    result = CliRunner().invoke(main, ["run", path, "--json", "--port", url], env={"ARMCTL_PORT": None})
    summary = json.loads(result.stdout.splitlines()[-1])
    assert (result.exit_code, summary["outcome"]) == (0, "finished"), summary
    assert ports[url].model.frames_dropped == 0
    assert ports[url].model.peak_fifo_occupancy <= fifo_frames


@pytest.mark.parametrize("fifo_frames", [2, 4])
def test_a_probed_small_connector_can_be_probed_again_installed(tmp_path, fifo_frames):
    """The installed command in fresh processes: probe, then probe and run again on the same arm."""
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    env["XDG_DATA_HOME"] = str(tmp_path / "data")
    url = f"sim://?clock=virtual&fifo={fifo_frames}"
    probe = [sys.executable, "-m", "armctl", "probe", "--no-motion", "--port", url]
    first = subprocess.run(probe, cwd=tmp_path, capture_output=True, text=True, timeout=50, env=env)
    assert first.returncode == 0, first.stderr
    kept = "not kept: connector.fifo_frames" in first.stdout + first.stderr
    assert kept == (fifo_frames < 3), first.stdout + first.stderr
    again = subprocess.run(probe, cwd=tmp_path, capture_output=True, text=True, timeout=50, env=env)
    assert again.returncode == 0, again.stderr
    (tmp_path / "job.txt").write_text("G90\nG1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X260\n")
    run = subprocess.run([sys.executable, "-m", "armctl", "run", "job.txt", "--json", "--port", url],
                         cwd=tmp_path, capture_output=True, text=True, timeout=50, env=env)
    assert run.returncode in (0, 1) and json.loads(run.stdout.splitlines()[-1])["frames_sent"] == 2, run.stderr
