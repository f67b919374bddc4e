"""Review of this morning's two changes: a corrupted report is a "blip" (armctl/core/job_readings.py,
commit 168b911) and the probe times a status frame by when it was built (armctl/probe/stream.py,
commit 8616c7a).  Each test here failed on the code it names.

A blip is a kind's reading *alone* between two equal readings of its kind.  A turn of the flange
(J6) changes joints 4-6 only (the tool point lies on its axis: the position and joints 1-3 read
as before), so a real wrist excursion is one kind's change with no other kind changed meanwhile.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from click.testing import CliRunner

from armctl.core.streamer import FRAME_SLACK_S, SLOWEST_ARM_FACTOR
from armctl.ui.cli import main
from test_resume_exactly_once import _open_one_arm

pytestmark = pytest.mark.timeout(60)

URL = "sim://?clock=virtual"
# A probed arm: the FIFO measured, the time bound's tolerance the probe's 1.05 (README)
PROBED_TOML = "[connector]\nfifo_frames = 200\nspeed_factor = 1.0\nspeed_tolerance = 1.05\n"


def _wrist_excursion(hold_ms: int, before_ms: int = 500) -> str:
    """Home, a rest, the flange turned 2 degrees and held ``hold_ms``, turned back, a 5 s delay."""
    return (f"G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 S1000 F30 H0\nG4 P{before_ms}\nG6 J6=2 F120 H0\n"
            f"G4 P{hold_ms}\nG6 J6=0\nG4 P5000\n")


def _run(tmp_path, monkeypatch, script: str, probed: bool):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "job.txt").write_text(script)
    if probed:
        (tmp_path / "armctl.toml").write_text(PROBED_TOML)
    ports = _open_one_arm(monkeypatch)
    result = CliRunner().invoke(main, ["run", "job.txt", "--json", "--port", URL], env={"ARMCTL_PORT": None})
    summary = json.loads(result.stdout.splitlines()[-1])
    executions = ports[URL].model.execution_log
    assert ports[URL].model.frames_dropped == 0
    return summary, executions[-1].end_s - executions[0].start_s


@pytest.mark.parametrize("probed", [False, True], ids=["document", "probed"])
def test_a_wrist_held_away_and_back_is_no_blip(tmp_path, monkeypatch, probed):
    """J6 at 2 degrees, read there in a dozen agreeing reports over 3 s, then back: the return
    was taken for the end of a blip (the reading before it was never re-read as the same kind's
    *changed* value), so the arm's motion dated from before the excursion — arm time 5.09 s for
    an arm the simulator's record shows working 8.83 s, and on a probed arm (speed_tolerance 1.05)
    "frames may have been lost" and 'fifo_frames looks wrong' though none was.  Before 168b911:
    finished, 8.885 s."""
    summary, arm_s = _run(tmp_path, monkeypatch, _wrist_excursion(3000), probed)
    assert summary["outcome"] == "finished", summary
    assert arm_s - 0.1 <= summary["arm_time_s"] <= arm_s + 0.6, (arm_s, summary)


def test_a_wrist_held_away_and_back_is_no_blip_installed(tmp_path):
    """The same, through the installed command in a fresh process, on the probed arm."""
    (tmp_path / "job.txt").write_text(_wrist_excursion(3000))
    (tmp_path / "armctl.toml").write_text(PROBED_TOML)
    done = subprocess.run([sys.executable, "-m", "armctl", "run", "job.txt", "--json", "--port", URL],
                          cwd=tmp_path, capture_output=True, text=True, timeout=50)
    summary = json.loads(done.stdout.splitlines()[-1])
    assert done.returncode == 0 and summary["outcome"] == "finished", (done.stderr, summary)
    assert summary["arm_time_s"] >= 8.7, summary  # the simulator's record: 8.83 s (above)


def test_a_wrist_turned_away_and_back_between_two_reports_is_no_blip(tmp_path, monkeypatch):
    """J6 at 2 degrees for 160 ms: read there once (joints 4-6 come every 270 ms), alone between
    two readings at 0 with no other kind changed — the blip rule's very picture of a corrupted
    report, yet the arm did it.  The motion then dates from before the excursion: on a probed arm
    'frames may have been lost' (arm time 5.09 s; the simulator's record 8.59 s).  Before 168b911:
    finished, 8.643 s.  The readings alone cannot tell the two apart; the frames written can: the
    reading came while a frame that turns the wrist there (J6 to 2 degrees) may still have been running (``Written.explains``)."""
    summary, arm_s = _run(tmp_path, monkeypatch, _wrist_excursion(160, before_ms=3100), probed=True)
    assert summary["outcome"] == "finished", summary
    assert arm_s - 0.1 <= summary["arm_time_s"] <= arm_s + 0.6, (arm_s, summary)


# --- the probe's speed_tolerance (armctl/probe/motion.py tolerance_finding) ---------------------

SLOW_HANDLING_ARM = "[timing]\ncommand_overhead_s = 0.050\n"  # the arm's own profile: 50 ms before every command


def _back_and_forth(frames: int) -> str:
    """1 mm moves back and forth, 10 ms each at 6000 mm/min (the bench's ``backforth``): every
    target repeats, so only time can confirm most of them."""
    moves = ["G1 X250 Y0 Z150 A180 B0 C0 S1500 F6000"]
    moves += [f"G1 X{251 if k % 2 == 0 else 250}" for k in range(frames - 1)]
    return "\n".join(moves) + "\n"


def test_the_probe_writes_the_tolerance_its_arm_needs_beyond_the_documents(tmp_path, monkeypatch):
    """An arm that takes 50 ms before every command: the probe measured that start delay (48.5 ms,
    so t = 3.43 by its own rule) and wrote 2.0, the document's default, "never above" it — and a job
    of 2000 repeated 10 ms moves on that probed arm then lost 141 frames to a full FIFO (time
    confirmed each at 2 x 10 + 20 ms where the arm takes 60) and ended "finished".  The probe may
    write up to the setting's own range (4).  Since it states the wait itself (command_overhead_s
    0.05, which the model then adds to every command), the tolerance covers what is left of the
    start delay (1.05), and the same job runs without loss."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "arm.toml").write_text(SLOW_HANDLING_ARM)
    (tmp_path / "job.txt").write_text(_back_and_forth(2000))
    url = "sim://?clock=virtual&profile=arm.toml"
    probed = subprocess.run([sys.executable, "-m", "armctl", "probe", "--port", url, "--yes", "--json"],
                            capture_output=True, text=True, timeout=50)  # kept with the arm (XDG_DATA_HOME: this test's)
    assert probed.returncode == 0, probed.stderr
    ports = _open_one_arm(monkeypatch)
    result = CliRunner().invoke(main, ["run", "job.txt", "--json", "--port", url], env={"ARMCTL_PORT": None})
    summary = json.loads(result.stdout.splitlines()[-1])
    assert (ports[url].model.frames_dropped, summary["outcome"]) == (0, "finished"), summary
    found = json.loads(probed.stdout)
    assert found["command_overhead_s"] == pytest.approx(0.05, abs=0.002), probed.stdout
    left_s = max(found["details"]["speed_factor"]["data"]["start_delay_s"]) - found["command_overhead_s"]
    assert found["speed_tolerance"] >= 1 + left_s * (SLOWEST_ARM_FACTOR - 1) / FRAME_SLACK_S, probed.stdout


def test_an_arm_beyond_the_documents_tolerance_never_ends_finished_with_frames_lost(tmp_path, monkeypatch):
    """Never probed, the same arm as above (50 ms before every command, so 6x slower than the model
    on 10 ms moves, 2x by the document): time confirms each repeated move at 40 ms where the arm
    takes 60, the host writes into a full FIFO, 141 of 2000 frames are dropped — and the job ends
    "finished" (exit 0; the FIFO of a sim:// arm counts as proven).  Nothing in the summary
    says so: the arm ends at the last target (the last frame is never the one dropped), the loss
    check only catches an arm too fast, and the slowness check needs two sightings along one
    frame, which a 10 ms move never gives.  The arm was seen working past the deadline ("kept
    working past the estimate"): with frames confirmed by time, that is the sign."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "arm.toml").write_text(SLOW_HANDLING_ARM)
    (tmp_path / "job.txt").write_text(_back_and_forth(2000))
    url = "sim://?clock=virtual&profile=arm.toml"
    ports = _open_one_arm(monkeypatch)
    result = CliRunner().invoke(main, ["run", "job.txt", "--json", "--port", url], env={"ARMCTL_PORT": None})
    summary = json.loads(result.stdout.splitlines()[-1])
    assert ports[url].model.frames_dropped > 0  # (141)
    assert summary["outcome"] != "finished", summary
    # the note names what is wrong: an arm slower than the time bound, not a smaller FIFO (it said
    # "fifo_frames = 200 … looks wrong … or the arm runs faster than speed_factor")
    notes = " ".join(summary["messages"])
    assert "speed_tolerance = 2" in notes and "looks too small" in notes and "fifo_frames" not in notes, notes


# --- when a status frame was built (armctl/probe/stream.py latest_built_s) -----------------------


def test_an_arm_that_builds_its_frames_up_to_a_millisecond_late_is_never_timed_before_it_built_them():
    """The module's promise rests on the arm building a frame exactly every period.  An arm whose
    own loop builds each frame up to 1 ms late (uniform), read promptly: the second earliest line
    through the frames near each one is a frame built early, so frames built late are put before
    they were built, by up to 0.96 ms (3 ms of jitter: up to 2.96 ms, and 1.3 ms early on
    average).  Read times alone were never early: the probe's start delays now come out short
    by about half the arm's jitter where they came out long by the reads' lateness."""
    import random

    from armctl.core.protocol import STATUS_ROTATION
    from armctl.probe.stream import latest_built_s

    class Frame:
        def __init__(self, kind: int) -> None:
            self.KIND = kind

    rng = random.Random(1)
    built = [0.5 + k * 0.030 + rng.uniform(0, 0.001) for k in range(1500)]
    frames = [(b, Frame(STATUS_ROTATION[k % len(STATUS_ROTATION)])) for k, b in enumerate(built)]
    bound = latest_built_s(frames, frames[0][0])
    assert len(bound) > 1400
    early_ms = max((b - bound[id(entry)]) * 1000 for entry, b in zip(frames, built) if id(entry) in bound)
    assert early_ms <= 0.0, f"a frame put {early_ms:.3f} ms before it was built"
