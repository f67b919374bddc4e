"""The arm's unknowns end to end: ``armctl run`` against every simulated arm the profile's
``[connector]`` table can describe, in virtual time.

The matrix: fifo_frames ∈ {50, 120, 200, 250} × control_frames ∈ {queued, arrival} ×
status_xyz_frame ∈ {worktable, robot} × speed_factor ∈ {0.7, 1.0, 1.3, 2.0}.  With the profile
(armctl.toml's ``[connector]``) matching the simulator, a job that sets a worktable origin (G54)
and ends in that frame drops no frame (the simulator's own counters) and ends ``done``.  The job
runs with a long lead, so the FIFO's capacity — not the lead — is what holds the streamer back.
"""

from __future__ import annotations

import itertools
import re
import subprocess
import sys

import pytest
from click.testing import CliRunner

import armctl.host.link
from armctl.ui.cli import main

FIFOS = (50, 120, 200, 250)
CONTROLS = ("queued", "arrival")
FRAMES = ("worktable", "robot")
FACTORS = (0.7, 1.0, 1.3, 2.0)
# The whole job fits in the lead and the line is fast: the FIFO bound is what binds.
LEAD_S, BAUD = "60", "115200"


def _job() -> str:
    """G54 to a fixture corner, then 300 short moves and delays inside it, ending there."""
    lines = ["G54 X200 Y-60 Z20", "G1 X10 Y10 Z30 A180 B0 C0 S1500 F3000"]
    for k in range(150):
        lines.append(f"G1 X{10 + k % 10} Y{10 + k // 10} Z30 F600")
        lines.append("G4 P50" if k % 3 else f"G1 Z{29 if k % 2 else 30} F600")
    lines.append("G1 X10 Y10 Z30 F3000")
    return "\n".join(lines) + "\n"


JOB_FRAMES = 303


@pytest.fixture
def job(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    path = tmp_path / "job.txt"
    path.write_text(_job(), encoding="utf-8")
    return path


@pytest.fixture
def opened_ports(monkeypatch):
    """Every port ``armctl`` opens (the sim:// ones carry ``.model``, the simulated arm)."""
    ports = []
    real_open = armctl.host.link.open_port

    def open_port(*args, **kwargs):
        port = real_open(*args, **kwargs)
        ports.append(port)
        return port

    monkeypatch.setattr(armctl.host.link, "open_port", open_port)
    return ports


def _profile(directory, fifo: int, control: str, frame: str, factor: float) -> None:
    (directory / "armctl.toml").write_text(
        f'[connector]\nfifo_frames = {fifo}\ncontrol_frames = "{control}"\nstatus_xyz_frame = "{frame}"\n'
        f"speed_factor = {factor}\n", encoding="utf-8")


def _url(fifo: int, control: str, frame: str, factor: float) -> str:
    return (f"sim://?clock=virtual&fifo_frames={fifo}&control_frames={control}&status_xyz_frame={frame}"
            f"&speed_factor={factor}")


@pytest.mark.parametrize("fifo, control, frame, factor", list(itertools.product(FIFOS, CONTROLS, FRAMES, FACTORS)))
def test_a_profile_that_matches_the_arm_drops_nothing_and_ends_done(job, opened_ports, fifo, control, frame, factor):
    _profile(job.parent, fifo, control, frame, factor)
    result = CliRunner().invoke(main, ["run", str(job), "--no-live", "--lead", LEAD_S, "--baud", BAUD,
                                       "--port", _url(fifo, control, frame, factor)])
    (port,) = opened_ports
    arm = port.model
    assert arm.frames_dropped == 0, result.output
    assert arm.frames_received.total == JOB_FRAMES
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
    # the FIFO was what held the streamer back: filled to its bound less the margin, never past it
    assert fifo - 8 <= arm.peak_fifo_occupancy <= fifo


def test_a_fresh_process_with_the_written_profile_ends_done(job):
    """The installed command, the [connector] table read from armctl.toml in the working directory."""
    _profile(job.parent, 50, "arrival", "robot", 1.3)
    log = job.parent / "run.jsonl"
    done = subprocess.run([sys.executable, "-m", "armctl", "run", str(job), "--no-live", "--lead", LEAD_S, "--baud", BAUD,
                           "--log", str(log), "--port", _url(50, "arrival", "robot", 1.3)],
                          capture_output=True, text=True, timeout=120, cwd=job.parent)
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.splitlines()[-1] == "finished: the arm finished the job"
    assert f"frames: {JOB_FRAMES} of {JOB_FRAMES} sent" in done.stdout


def test_a_fifo_smaller_than_the_profile_says_ends_frames_may_have_been_lost(job, opened_ports):
    """The profile's document default (200) against an arm that holds 50: the streamer trusts the
    profile and the arm drops frames.  The run never says done: it ends "frames may have been
    lost", exit 1, with the evidence (the arm skipped frames faster than they could run), and it
    claims no line executed from the first frame dropped on (the time bound alone cannot tell a
    dropped frame from a run one)."""
    result = CliRunner().invoke(main, ["run", str(job), "--no-live", "--lead", LEAD_S, "--baud", BAUD,
                                       "--port", "sim://?clock=virtual&fifo=50"])
    (port,) = opened_ports
    dropped = port.model.dropped_indexes
    assert dropped
    assert result.exit_code == 1, result.output
    assert "finished: the arm finished" not in result.stdout
    assert "stopped: frames may have been lost" in result.output
    assert "they were skipped (dropped by a full FIFO, or cleared)" in result.output
    assert re.search(r"frames confirmed by the arm's reports: \d+; by time only: \d+", result.stdout)
    known = int(re.search(r"last line known executed: (\d+)", result.stdout).group(1))
    assert known <= min(dropped)  # line = frame index + 1 in this job: the first dropped line is not claimed
    resume = int(re.search(r"--from-line (\d+)", result.stdout).group(1))
    assert resume == known + 1


# --- without a probe: never `done` after a loss that the time alone reveals ---------------------


@pytest.mark.parametrize("fifo, control, frame, factor", [
    (50, "queued", "worktable", 1.0), (50, "arrival", "robot", 0.7), (50, "queued", "robot", 2.0),
    (120, "arrival", "worktable", 1.3), (120, "queued", "worktable", 0.7), (120, "arrival", "robot", 2.0),
])
def test_an_unprobed_profile_on_a_smaller_fifo_never_ends_done(job, opened_ports, fifo, control, frame, factor):
    """The profile says only what the arm's control mode and status frame are (the FIFO stays the
    document's 200, unprobed); the arm holds fewer and drops.  Whatever the arm's pace, the run
    ends "frames may have been lost", exit 1, and claims no dropped line executed."""
    (job.parent / "armctl.toml").write_text(
        f'[connector]\ncontrol_frames = "{control}"\nstatus_xyz_frame = "{frame}"\nspeed_factor = {factor}\n',
        encoding="utf-8")
    result = CliRunner().invoke(main, ["run", str(job), "--no-live", "--lead", LEAD_S, "--baud", BAUD,
                                       "--port", _url(fifo, control, frame, factor)])
    (port,) = opened_ports
    dropped = port.model.dropped_indexes
    assert dropped, result.output
    assert result.exit_code == 1, result.output
    assert "stopped: frames may have been lost" in result.output
    known = re.search(r"last line known executed: (\d+|none)", result.stdout).group(1)
    assert known == "none" or int(known) <= min(dropped)


def test_the_fifo_is_proven_by_a_probe_or_a_simulator_that_holds_at_least_the_profiles():
    from armctl.host.link import fifo_proven
    from armctl.host.profile import default_profile, parse_profile

    document = default_profile().connector  # 200, the document's, not measured
    assert fifo_proven("sim://", document)  # the simulator holds 200 unless told otherwise
    assert fifo_proven("sim://?clock=virtual&fifo_frames=250", document)
    assert not fifo_proven("sim://?clock=virtual&fifo_frames=50", document)
    assert not fifo_proven("sim://?fifo=199", document)  # the alias says the same
    assert not fifo_proven("/dev/ttyUSB0", document)
    assert not fifo_proven("socket://localhost:7777", document)
    probed = parse_profile({"connector": {"fifo_frames": 50}}).connector
    assert fifo_proven("/dev/ttyUSB0", probed)


def test_a_fresh_process_on_a_smaller_fifo_without_a_probe_says_frames_may_have_been_lost(job):
    done = subprocess.run([sys.executable, "-m", "armctl", "run", str(job), "--no-live", "--lead", LEAD_S, "--baud", BAUD,
                           "--port", "sim://?clock=virtual&fifo_frames=50"],
                          capture_output=True, text=True, timeout=120, cwd=job.parent)
    assert done.returncode == 1, done.stdout + done.stderr
    assert done.stderr.splitlines()[-1] == "stopped: frames may have been lost"
    assert re.search(r"^frames confirmed by the arm's reports: \d+; by time only: \d+"
                     r"(; gone from the buffer, not seen running: \d+)?$", done.stdout, re.M)
    assert "Traceback" not in done.stderr


def test_a_long_run_of_frames_that_move_nothing_is_no_false_alarm(tmp_path, monkeypatch):
    """200 delays after the last move (more than the engine keeps of recent frames): the arm time
    counts every one of them, so the job's time is no sign of loss, and the run is done."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    (tmp_path / "job.txt").write_text("G1 X200 Y0 Z250 A180 B0 C0 S1500 F3000\n" + "G4 P500\n" * 200)
    result = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--port", "sim://?clock=virtual"])
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
    actual, estimated = map(float, re.search(r"arm time: ([\d.]+) s .*estimated ([\d.]+) s", result.stdout).groups())
    assert actual == pytest.approx(estimated, rel=0.02)
