"""H5 in the summary: how an arm takes control frames (queued in the FIFO, or acted on as they
land) is the document's guess until measured, and an arm that acts on a POSE as it lands cuts
short the move before it — then rests at the job's last target all the same.

Found by a review: on ``sim://?clock=virtual&control=arrival`` with the default profile
(``control_frames = "queued"``), scripts/pick_and_place.txt's last G1 was interrupted by its
closing POSE 0 (26.4 s of arm time for 31.2 s estimated), and the run said ``finished``, exit 0.
A job that sent control frames now needs ``control_frames`` measured or set (or a simulator that
says its own): otherwise it ends ``finished, unproven``, exit 1, and says why.  Judged by the
simulator's own record; the installed command in a fresh process.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.core.protocol import GoToPose, LinearMove
from armctl.host.profile import default_profile, with_connector
from armctl.sim.executor import DONE
from armctl.ui.cli import main
from test_resume_exactly_once import _open_one_arm

pytestmark = pytest.mark.timeout(60)

JOB = Path(__file__).resolve().parents[1] / "scripts" / "pick_and_place.txt"
ARRIVAL = "sim://?clock=virtual&control=arrival"


def _run(*args: str, cwd: Path) -> tuple[dict, subprocess.CompletedProcess]:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    done = subprocess.run([sys.executable, "-m", "armctl", "run", str(JOB), "--json", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=50)
    return json.loads(done.stdout.splitlines()[-1]), done


def test_an_arrival_arm_the_profile_calls_queued_ends_unproven_and_says_why(tmp_path, monkeypatch):
    summary, done = _run("--port", ARRIVAL, cwd=tmp_path)
    assert (summary["outcome"], done.returncode) == ("finished, unproven", 1), done.stdout + done.stderr
    (said,) = [m for m in summary["messages"] if m.startswith("finished, unproven")]
    assert "the job sent 1 control frame (POSE, PROGRAM, G54 …)" in said and "run `armctl probe` once" in said
    # the simulator's record: the move before the POSE was cut short, as the note warns
    monkeypatch.chdir(tmp_path)
    ports = _open_one_arm(monkeypatch)
    CliRunner().invoke(main, ["run", str(JOB), "--no-live", "--port", ARRIVAL], env={"ARMCTL_PORT": None})
    log = ports[ARRIVAL].model.execution_log
    before_pose = [e for e in log if isinstance(e.command, LinearMove)][-1]
    assert before_pose.outcome != DONE and any(isinstance(e.command, GoToPose) for e in log)


def test_a_profile_that_says_arrival_or_a_simulator_that_says_queued_proves_it(tmp_path):
    (tmp_path / "armctl.toml").write_text('[connector]\ncontrol_frames = "arrival"\n')
    summary, done = _run("--port", ARRIVAL, cwd=tmp_path)
    assert (summary["outcome"], done.returncode) == ("finished", 0), done.stdout + done.stderr
    (tmp_path / "armctl.toml").unlink()
    summary, done = _run("--port", "sim://?clock=virtual", cwd=tmp_path)  # queued, as the document guesses
    assert (summary["outcome"], done.returncode) == ("finished", 0), done.stdout + done.stderr


def test_a_lone_control_frame_has_no_move_before_it_to_cut_short(tmp_path):
    # armctl home is one POSE 0: acted on as it lands or queued, it is the same
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    done = subprocess.run([sys.executable, "-m", "armctl", "home", "--json", "--port", ARRIVAL], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=50)
    assert json.loads(done.stdout.splitlines()[-1])["outcome"] == "finished", done.stdout + done.stderr


def test_control_frames_proven_by_measure_or_by_the_port():
    document = default_profile().connector
    assert document.control_frames_proven("queued") and not document.control_frames_proven("arrival")
    assert not document.control_frames_proven(None)  # a real arm, never probed
    probed = with_connector(default_profile(), {"control_frames": "queued"}, "probed on 2026-11-28").connector
    assert probed.control_frames_proven(None) and probed.control_frames_proven("arrival")  # (the measure wins)
