"""Issue 26 item 6: the words a newcomer reads.

The text summary says ``finished`` as the JSON does; ``probe`` prints TOML spellings; after a
pause and a feed override the summary says that they explain the difference from the estimate;
``status --watch --json`` starts with a complete record and every record carries its time.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from armctl import Arm, JobObserver
from armctl.ui.run_job import Departures

ARMCTL = Path(sys.executable).with_name("armctl")
VIRTUAL = "sim://?clock=virtual"


def armctl(*args: str, cwd: Path, timeout: float = 50) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    return subprocess.run([str(ARMCTL), *args], capture_output=True, text=True, timeout=timeout, cwd=cwd, env=env)


@pytest.mark.timeout(60)
def test_text_summary_says_finished_like_the_json(tmp_path):
    job = tmp_path / "job.txt"
    job.write_text("G4 P100\n")
    text = armctl("run", str(job), "--port", VIRTUAL, "--no-live", cwd=tmp_path)
    assert text.returncode == 0, text.stderr
    assert text.stdout.splitlines()[-1] == "finished: the arm finished the job"
    assert any(line.startswith("arm time: ") for line in text.stdout.splitlines())  # what the shared hook reads
    as_json = armctl("run", str(job), "--port", VIRTUAL, "--json", cwd=tmp_path)
    assert json.loads(as_json.stdout.splitlines()[-1])["outcome"] == "finished"


@pytest.mark.timeout(120)
def test_probe_prints_toml_spellings(tmp_path):
    done = armctl("probe", "--port", VIRTUAL + "&control_frames=arrival", "--no-motion", "--write", "armctl.toml",
                  cwd=tmp_path, timeout=110)
    assert done.returncode == 0, done.stderr
    wrote = next(line for line in done.stdout.splitlines() if line.startswith("wrote [connector]"))
    assert 'control_frames = "arrival"' in wrote and "kinematics_verified = false" in wrote
    assert "'" not in wrote and "True" not in wrote and "False" not in wrote


class _Followed(JobObserver):
    def __init__(self) -> None:
        self.departures = Departures()

    def update(self, view) -> None:
        self.departures.update(view)


@pytest.mark.timeout(60)
def test_a_pause_and_a_feed_override_explain_the_difference():
    seen: dict = {}
    observer = _Followed()

    def on_progress(progress):
        if progress.frames_sent >= 2 and "override" not in seen:
            seen["override"] = arm.feed_override(120)
        if progress.frames_sent >= 3 and "pause" not in seen:
            seen["pause"] = arm.pause()
        elif progress.paused and "paused_s" not in seen:
            seen["paused_s"] = progress.elapsed_s
        elif "paused_s" in seen and "resume" not in seen and progress.elapsed_s - seen["paused_s"] >= 3.0:
            seen["resume"] = arm.resume()

    with Arm.open(VIRTUAL) as arm:
        x, y, z = arm.status().position_mm
        lines = [f"G1 X{x + 20 * (k % 2):.1f} Y{y + 2 * k:.1f} Z{z:.1f} F1200" for k in range(1, 9)]
        lines[0] += " A180 B0 C0 S1500"
        result = arm.run("".join(line + "\n" for line in lines), on_progress=on_progress, observer=observer, timeout=60)
    assert result.finished and seen["override"] == 120
    departures = observer.departures
    assert departures.paused_s >= 3.0 and departures.feed_percents == {120}
    text = departures.explanation()
    assert text.startswith("the estimate assumes no pause and 100 % feed: this job was paused ")
    assert text.endswith("and ran at 120 % feed for part of it, which explain the difference")


def test_no_explanation_when_nothing_departed():
    assert Departures().explanation() == ""


@pytest.mark.timeout(60)
def test_status_watch_json_starts_complete_and_carries_time(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    watch = subprocess.Popen([str(ARMCTL), "status", "--watch", "--json", "--port", "sim://"], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=env)
    try:
        records = [json.loads(watch.stdout.readline()) for _ in range(3)]
    finally:
        watch.kill()
        watch.wait(timeout=10)
    first = records[0]
    assert None not in (first["x"], first["y"], first["z"], first["paused"], first["pwm"], *first["joints"], *first["worktable"])
    times = [record["t"] for record in records]
    assert times[0] == 0 and times == sorted(times) and times[-1] > 0


def test_the_text_summary_prints_the_explanation_under_the_arm_time(capsys):
    from types import SimpleNamespace

    from armctl.host.api import RunResult
    from armctl.ui.run_job import JobOptions, _summary

    result = RunResult("finished", 8, 8, 8, 8, 31.2, 18.1, None)
    view = SimpleNamespace(arm_time_s=31.2)
    options = JobOptions("job.txt", None, None, 2.0, 1, False, None, False, "pause", None, 3.0)
    code = _summary(result, view, 1.0, SimpleNamespace(job_s=27.6), options,
                    "the estimate assumes no pause and 100 % feed: this job was paused 8.0 s, which explains the difference")
    lines = capsys.readouterr().out.splitlines()
    assert code == 0
    assert lines[2] == "arm time: 31.2 s from the first frame to the arm at rest; estimated 27.6 s (+13.0%)"
    assert lines[3] == "  (the estimate assumes no pause and 100 % feed: this job was paused 8.0 s, which explains the difference)"
