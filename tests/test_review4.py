"""Review of three rules that change what a job's summary claims: the not-begun sign
(``Losses.check_not_begun``), moving past the time bound (``Losses.moved_past_time_bound``) and
blips (armctl/core/job_readings.py, ``Written.explains``).  Each test here failed on the code it
names; the simulator's own record (``frames_dropped``, ``execution_log``) is the truth."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from test_resume_exactly_once import _open_one_arm
from test_review3 import SLOW_HANDLING_ARM, _back_and_forth

pytestmark = pytest.mark.timeout(60)

URL = "sim://?clock=virtual"
NOISY = "&loss=0.1&corrupt=0.05&noise=0.02&seed={seed}"
ROTATION_S = 0.27  # nine kinds, 30 ms apart: a reading of each kind comes at most this late


def _run(tmp_path, monkeypatch, script: str, options: str = "", toml: str | None = None):
    """``armctl run --json`` on a simulated arm: the summary, the simulator's frames dropped and
    refused, and its arm time (first frame's start to last frame's end)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "job.txt").write_text(script)
    if toml is not None:
        (tmp_path / "armctl.toml").write_text(toml)
    ports = _open_one_arm(monkeypatch)
    url = URL + options
    result = CliRunner().invoke(main, ["run", "job.txt", "--json", "--port", url], env={"ARMCTL_PORT": None})
    summary = json.loads(result.stdout.splitlines()[-1])
    model = ports[url].model
    log = model.execution_log
    refused = sum(1 for entry in log if entry.outcome == "refused")
    return summary, model.frames_dropped, refused, log[-1].end_s - log[0].start_s


# --- blips: a frame whose time bound never runs out (Written.explains) -------------------------

# An SD program: its time bound is infinite (TimeBound.program_time_unknown), and the arm's
# reports prove it finished long before the end (the arm seen on the frames after it).
PROGRAM_FIRST = """G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000
PROGRAM 1
POSE 1
G1 X213.8 Y1.8 Z143.5 A180 B0 C0 F3000
G1 X240.3 Y105.9 Z93.2 A180 B0 C0 F300
"""


@pytest.mark.parametrize("seed", [3, 10, 15, 18, 23])
def test_an_sd_program_long_finished_never_explains_a_blip(tmp_path, monkeypatch, seed):
    """PROGRAM 1, then three moves on a line with 10 % of the status frames lost and 5 %
    corrupted: the PROGRAM's time bound never runs out, and ``Written.explains`` reads only that
    (an SD program's motion is the arm's own: it "explains" any reading), so after it no corrupted
    report was ever taken for a blip — the arm time ran past the simulator's record (31.99 s) by
    2.37, 1.35, 1.01, 1.17 and 1.05 s on these seeds (0.09-0.29 s on the others around them),
    though the arm was seen on the frames after the PROGRAM half a minute before.  A frame the
    lower bound passed before a reading was read (reports read earlier were built earlier) cannot
    explain it."""
    summary, dropped, refused, arm_s = _run(tmp_path, monkeypatch, PROGRAM_FIRST, NOISY.format(seed=seed))
    assert (dropped, refused, summary["outcome"]) == (0, 0, "finished"), summary
    assert arm_s - 0.1 <= summary["arm_time_s"] <= arm_s + 2 * ROTATION_S + 0.1, (arm_s, summary)


def test_an_sd_program_long_finished_never_explains_a_blip_installed(tmp_path):
    """The same (seed 3), through the installed command in a fresh process: the simulator's
    record is 31.99 s of arm time (above); the summary said 34.37 s."""
    (tmp_path / "job.txt").write_text(PROGRAM_FIRST)
    done = subprocess.run([sys.executable, "-m", "armctl", "run", "job.txt", "--json", "--port", URL + NOISY.format(seed=3)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=50)
    summary = json.loads(done.stdout.splitlines()[-1])
    assert done.returncode == 0 and summary["outcome"] == "finished", (done.stderr, summary)
    assert 31.89 <= summary["arm_time_s"] <= 31.99 + 2 * ROTATION_S + 0.1, summary


JOINT_MOVES_BETWEEN_LINES = """G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000
G1 X234.6 Y82.8 Z86.2 A180 B0 C0 F3000
G6 J1=-6.8 J2=19.0 J3=-15.9 J4=0 J5=90 J6=-3.3 F20
G1 X235.0 Y119.7 Z92.7 A180 B0 C0 F6000
G1 X283.6 F6000
G4 P8000
G1 X221.9 Y68.2 Z147.9 A180 B0 C0 F1500
G54 X0 Y0 Z10
G1 X227.8 Y60.1 Z171.0 A180 B0 C0 F6000
G1 S2000
G1 X275.2 Y61.6 Z133.9 A180 B0 C0 F6000
G6 J1=25.7 J2=13.9 J3=15.8 J4=0 J5=90 J6=13.9 F45
G1 X226.4 Y45.3 Z168.3 A180 B0 C0 F6000
"""


@pytest.mark.parametrize("seed", [1, 2])
def test_a_joint_move_from_a_cartesian_end_does_not_explain_corrupted_reports_for_ever(tmp_path, monkeypatch, seed):
    """The README's noisy line (5 % lost, 2 % corrupted): the simulator's record is 26.01 s of arm
    time; the summary says 59.28 s (seed 1) and 48.92 s (seed 2), with "the arm kept working past
    the estimate".  The last G6 starts at joints only the arm's own IK knows (``path_known``
    False), so ``Written.explains`` takes it for passing anywhere until its time bound — which
    allows a start anywhere within the joint limits, some 30 s — runs out; the lower bound cannot
    pass it (no stream judges it), so no corrupted report after it is a blip, each one restarts
    the rest proof, and the end waits for a quiet stretch."""
    summary, dropped, refused, arm_s = _run(tmp_path, monkeypatch, JOINT_MOVES_BETWEEN_LINES,
                                            f"&loss=0.05&corrupt=0.02&noise=0.02&seed={seed}")
    assert (dropped, refused, summary["outcome"]) == (0, 0, "finished"), summary
    assert summary["arm_time_s"] <= arm_s + 2 * ROTATION_S + 0.1, (arm_s, summary)


def test_a_joint_move_from_a_cartesian_end_does_not_explain_corrupted_reports_for_ever_installed(tmp_path):
    """The same (seed 1), through the installed command in a fresh process: the simulator's record
    is 26.01 s of arm time; the summary said 59.28 s.  Now the arm at rest at the end of exactly
    one frame not known finished proves it and every one before it ran (``Written.rests_at``)."""
    (tmp_path / "job.txt").write_text(JOINT_MOVES_BETWEEN_LINES)
    url = URL + "&loss=0.05&corrupt=0.02&noise=0.02&seed=1"
    done = subprocess.run([sys.executable, "-m", "armctl", "run", "job.txt", "--json", "--port", url],
                          cwd=tmp_path, capture_output=True, text=True, timeout=50)
    summary = json.loads(done.stdout.splitlines()[-1])
    assert done.returncode == 0 and summary["outcome"] == "finished", (done.stderr, summary)
    assert 25.91 <= summary["arm_time_s"] <= 26.01 + 2 * ROTATION_S + 0.1, summary


def test_the_arm_time_counts_a_delay_after_an_sd_program(tmp_path, monkeypatch):
    """PROGRAM 1 (4 s on the simulator, which moves nothing) then G4 P5000: the arm time is 13.99 s
    where the simulator's record is 17.94 s (the delay ends at 18.78 s, the first frame began at
    0.84 s).  ``Arrival.done_at`` counts from the last motion seen plus the model's time of the
    frames after it, in which the PROGRAM counts for nothing; its run position's activity
    (``active_s``) ends when the program does, 5 s before the delay."""
    script = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X250 Y50 Z120 F600\nPROGRAM 1\nG4 P5000\n"
    summary, dropped, refused, arm_s = _run(tmp_path, monkeypatch, script)
    assert (dropped, refused, summary["outcome"]) == (0, 0, "finished"), summary
    assert arm_s - 0.1 <= summary["arm_time_s"] <= arm_s + 2 * ROTATION_S + 0.1, (arm_s, summary)


# --- the not-begun sign (Losses.check_not_begun): a refused target it cannot see ---------------


REFUSED_BETWEEN_LINES = ("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X241.2 Y-83.3 Z121.4 F1500\n"
                         "G1 X500 Y0 Z150 F3000\nG1 X210.0 Y-97.1 Z122.3 F1500\n")


@pytest.mark.parametrize("seed", [2, 3, 4, 12])
def test_one_lost_or_corrupted_report_never_lets_time_count_a_refused_target_done(tmp_path, monkeypatch, seed):
    """G1 X500 (refused: the arm does not move) between two reachable lines, on a line with 10 %
    of the status frames lost and 5 % corrupted: 17 of seeds 0-59 ended "finished", exit 0.  Time
    was held off the refused frame only from two agreeing reports at its start in the last rotation
    before its deadline, and only while each report after them said so again: one report lost or
    corrupted there (seed 2: the last agreeing pair at 17.28 s, a corrupted report at 17.55 s, the
    next two lost, the deadline 18.10 s) and time counted it done before two reports after the
    deadline could say it stood.  Only reports that agree on the arm being elsewhere (two in a row:
    corrupted ones never agree) show that it left the start."""
    summary, dropped, refused, _ = _run(tmp_path, monkeypatch, REFUSED_BETWEEN_LINES, NOISY.format(seed=seed))
    assert (dropped, refused) == (0, 1)
    assert summary["outcome"] == "frames may have been lost" and summary["exit_code"] == 1, summary
    assert any("stood at the start of frame 3 (line 3)" in m for m in summary["messages"]), summary["messages"]


def test_one_lost_or_corrupted_report_never_lets_time_count_a_refused_target_done_installed(tmp_path):
    """The same (seed 2), through the installed command in a fresh process: exit 1, the refused line named."""
    (tmp_path / "job.txt").write_text(REFUSED_BETWEEN_LINES)
    done = subprocess.run([sys.executable, "-m", "armctl", "run", "job.txt", "--json", "--port", URL + NOISY.format(seed=2)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=50)
    summary = json.loads(done.stdout.splitlines()[-1])
    assert done.returncode == 1 and summary["outcome"] == "frames may have been lost", (done.stderr, summary)
    assert any("stood at the start of frame 3 (line 3)" in m for m in summary["messages"]), summary["messages"]


REFUSED_AFTER = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\n{before}\nG1 X500 Y0 Z150 A180 B0 C0 F3000\nG1 X250 Y-100 Z100 F3000\n"


@pytest.mark.parametrize("before", ["POSE 1", "G6 J1=10 J2=0 J3=0 J4=0 J5=90 J6=0 F30"], ids=["pose", "joint-move"])
def test_a_target_refused_after_a_joint_move_never_ends_finished(tmp_path, monkeypatch, before):
    """G1 X500 (out of the simulated arm's reach: refused, the arm does not move) right after a
    POSE or a joint move, then a reachable move: the job ends "finished", exit 0 — the README says
    a refused target ends exit 1.  The not-begun sign cannot see it: the line's start is where only
    the profile's unverified kinematics put the joint move's end (``path_known`` False, so
    ``standing_at_start`` says nothing), and the joint move's own time bound allows a start
    anywhere within the joint limits (29 s here), so the lower bound is still on the joint move
    when the arm comes to rest at the last target, whose rest then proves every frame ran.
    (After ``G1 X260`` instead, the same X500 ends "frames may have been lost", as it should.)
    Now such a move needs two reports on its path, or inside the next one's (``Ledger.prove_ran``):
    without them the job ends "finished, unproven", naming it."""
    summary, dropped, refused, _ = _run(tmp_path, monkeypatch, REFUSED_AFTER.format(before=before))
    assert (dropped, refused) == (0, 1)
    assert summary["outcome"] != "finished" and summary["exit_code"] == 1, summary
    assert any("frame 3 (line 3)" in m for m in summary["messages"]), summary["messages"]


def test_a_target_refused_after_an_sd_program_never_ends_finished(tmp_path, monkeypatch):
    """The same G1 X500 right after a PROGRAM: the line starts wherever the SD program left the
    arm (``TimeBound.starts_where_a_program_left``: ``path_known`` False), so the not-begun sign
    cannot see it either — it ended "finished", exit 0."""
    summary, dropped, refused, _ = _run(tmp_path, monkeypatch, REFUSED_AFTER.format(before="PROGRAM 1"))
    assert (dropped, refused) == (0, 1)
    assert summary["outcome"] != "finished" and summary["exit_code"] == 1, summary
    assert any("frame 3 (line 3)" in m for m in summary["messages"]), summary["messages"]


def test_a_target_refused_after_a_joint_move_never_ends_finished_installed(tmp_path):
    """The same (after the joint move), through the installed command in a fresh process."""
    (tmp_path / "job.txt").write_text(REFUSED_AFTER.format(before="G6 J1=10 J2=0 J3=0 J4=0 J5=90 J6=0 F30"))
    done = subprocess.run([sys.executable, "-m", "armctl", "run", "job.txt", "--json", "--port", URL],
                          cwd=tmp_path, capture_output=True, text=True, timeout=50)
    summary = json.loads(done.stdout.splitlines()[-1])
    assert done.returncode == 1 and summary["outcome"] != "finished", (done.stderr, summary)
    assert any("frame 3 (line 3)" in m for m in summary["messages"]), summary["messages"]


# --- moving past the time bound (Losses.moved_past_time_bound) ------------------------------------


def test_a_slow_arm_is_not_hidden_by_a_long_delay_at_the_end(tmp_path, monkeypatch):
    """tests/test_review3.py's arm that takes 50 ms before every command, never probed, and its
    2000 repeated 10 ms moves: 141 dropped by a full FIFO, and the job ends "frames may have been
    lost" because the arm still moved after every frame's time bound.  A G4 P20000 after them hid
    it: the bound the arm's motion was compared with was the latest of every frame's, the delay's
    included (its 20 s at 2x), so the arm's last 12 s of draining its full FIFO fell inside it —
    142 dropped, and "finished", exit 0.  A delay moves nothing: motion after the time bound of
    the last frame that moves the arm is the sign."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "arm.toml").write_text(SLOW_HANDLING_ARM)
    summary, dropped, refused, _ = _run(tmp_path, monkeypatch, _back_and_forth(2000) + "G4 P20000\n",
                                        f"&profile={tmp_path / 'arm.toml'}")
    assert dropped > 0  # (142)
    assert summary["outcome"] == "frames may have been lost", summary
    assert any("still moved after" in m for m in summary["messages"]), summary["messages"]


def test_a_slow_arm_is_not_hidden_by_a_long_delay_at_the_end_installed(tmp_path):
    """The same, through the installed command in a fresh process: exit 1, not 0."""
    (tmp_path / "arm.toml").write_text(SLOW_HANDLING_ARM)
    (tmp_path / "job.txt").write_text(_back_and_forth(2000) + "G4 P20000\n")
    done = subprocess.run([sys.executable, "-m", "armctl", "run", "job.txt", "--json", "--port",
                           f"{URL}&profile=arm.toml"], cwd=tmp_path, capture_output=True, text=True, timeout=50)
    summary = json.loads(done.stdout.splitlines()[-1])
    assert done.returncode == 1 and summary["outcome"] == "frames may have been lost", (done.stderr, summary)


# --- a false alarm before the first frame: a corrupted worktable report -------------------------


def test_a_corrupted_worktable_report_at_the_start_raises_no_alarm(tmp_path, monkeypatch):
    """Seed 99 on a noisy line: the last worktable-origin report before the job starts is corrupted
    (Y 2969.6 mm; the arm's origin is 0), and the start pose takes it — the origin kind is not one
    ArmState holds back (only position and joints are judged), and read_arm's two extra rotations
    replace a corrupted *first* report, not a last one.  The first move is then planned ~3 m long
    (estimate 93.7 s for a job of 42.4 s), and the gap check says 'the arm got from frame 1 to
    frame 6 in 3.24 s, but the 4 frames between take 57.96 s of motion: they were skipped' —
    "frames may have been lost", exit 1, on an arm that lost nothing (seed 98: finished)."""
    script = ("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG54 X0 Y0 Z0\nG1 X298.3 Y77.3 Z199.8 A180 B0 C0 F3000\n"
              "G1 S1000\nG4 P100\nG1 X280 Y0 Z60 A180 B0 C0 F3000\nG300 X250 Y30 Z60 R30 F900\n"
              "G301 X220 Y0 Z60 F900\nG4 P100\nPROGRAM 2\nPOSE 1\nPOSE 0\nG1 X234.9 Y-80.0 Z95.6 A180 B0 C0 F600\n")
    summary, dropped, refused, _ = _run(tmp_path, monkeypatch, script, NOISY.format(seed=99))
    assert (dropped, refused) == (0, 0)
    assert summary["outcome"] != "frames may have been lost", summary
