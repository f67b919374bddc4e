"""Review of the arm on the wall clock (session 6), as someone with a real arm on their desk meets
it: the installed command in fresh processes, against ``armctl sim --pty`` where the fault needs
the wall clock, in virtual time where it does not.

- The ETA of a line-bound job: 301 moves of 4 ms each at 9600 baud take 15.1 s (the line carries a
  frame every 50 ms), and ``run`` said ``ETA 0:01`` two seconds in (``eta_s`` 1.02 at 2.58 s in
  ``--json``): the ETA counted the motion still unsent (3.2 s in all) and never the line it has to
  cross.  Now it is at least the unsent frames' time on the line.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.timeout(60)


def _env(tmp_path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    env["XDG_DATA_HOME"] = str(tmp_path / "data")  # no probe record of another test's arm
    return env


def _tiny_job(tmp_path, moves: int = 300):
    """``moves`` moves of 0.2 mm (4 ms each at 3000 mm/min): line-bound, a frame every 50 ms."""
    lines = ["G1 X200 Y0 Z200 A180 B0 C0 S1500 F3000"] + [f"G1 X{200.2 if i % 2 == 0 else 200}" for i in range(moves)]
    path = tmp_path / "tiny.txt"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_the_eta_of_a_line_bound_job_counts_the_line(tmp_path):
    script = _tiny_job(tmp_path)
    done = subprocess.run([sys.executable, "-m", "armctl", "run", str(script), "--port", "sim://?clock=virtual", "--json"],
                          capture_output=True, text=True, timeout=50, env=_env(tmp_path), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    events = [json.loads(line) for line in done.stdout.splitlines()]
    estimated_s = events[0]["estimated_job_s"]
    assert estimated_s == pytest.approx(15.1, abs=0.1)
    progress = [event for event in events if event["event"] == "progress"]
    assert len(progress) > 10
    for event in progress:  # elapsed + ETA: the job's time, whenever it is read (the arm keeps the model's pace)
        left_frames = event["total_frames"] - event["frames_sent"]
        assert event["eta_s"] >= left_frames * 0.05 - 1e-6, event
        assert event["elapsed_s"] + event["eta_s"] == pytest.approx(estimated_s, rel=0.1), event


# --- a pty's path is no arm ----------------------------------------------------------------------
# `armctl probe` keeps what it measured with the arm's identity; a pty's was its path, and the
# kernel gives a path to the next pty as soon as the last one closes: `armctl sim --pty` stopped and
# another started (`--url sim://?fifo=20`) is on /dev/pts/1 again, and took the first one's probe.
# The tiny job on it then dropped 20 frames (`sim --stats`: "dropped": 20) and ended `finished`,
# exit 0 — a FIFO size "proven" by the probe of another arm.

PROBED = {"fifo_frames": 200, "control_frames": "queued", "status_xyz_frame": "worktable", "speed_factor": 1.0,
          "kinematics_verified": True, "speed_tolerance": 1.3, "command_overhead_s": 0.0}


def _keep_probe(port: str, data_home) -> None:
    """What `armctl probe --yes` keeps for the default arm on ``port`` (tmp/rt measured these)."""
    from armctl.host import calibration

    findings = [(name, value, "measured", "sure") for name, value in PROBED.items()]
    record = calibration.calibration_of(port, calibration.arm_identity(port), findings, "2026-11-28", 9600)
    calibration.save(record, data_home / "armctl" / calibration.STORE_FOLDER)


def _same_pty_twice():
    """Two ptys one after the other on one path (the kernel reuses the lowest free number at once;
    another process may take it in between: tried again)."""
    from armctl.host.calibration import arm_identity

    for _ in range(50):
        master, slave = os.openpty()
        path = os.ttyname(slave)
        first = (arm_identity(path), arm_identity(path))
        os.close(slave), os.close(master)
        time.sleep(0.05)  # the kernel's coarse clock: a pty made within its tick (~4 ms) has the last one's time
        master, slave = os.openpty()
        try:
            if os.ttyname(slave) == path:
                return path, first, arm_identity(path)
        finally:
            os.close(slave), os.close(master)
    pytest.fail("the kernel never gave a pty's path to the next one")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux ptys (/dev/pts/N)")
def test_the_next_pty_on_a_path_is_another_arm():
    path, (first, again), next_one = _same_pty_twice()
    assert first == again  # one pty: one arm, however often it is asked
    assert next_one != first, path


def _sim_pty(tmp_path, url: str, stats: str):
    import re

    process = subprocess.Popen([sys.executable, "-m", "armctl", "sim", "--pty", "--url", url, "--stats", str(tmp_path / stats)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env(tmp_path))
    ready = process.stdout.readline()
    found = re.fullmatch(r"simulated arm on (/dev/pts/\d+) \(Ctrl-C to stop\)\n", ready)
    assert found, ready + process.stderr.read()
    return process, found.group(1)


def _stop(process) -> None:
    import signal

    process.send_signal(signal.SIGINT)
    assert process.wait(timeout=10) == 130
    process.communicate()


@pytest.mark.realtime
@pytest.mark.timeout(60)
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux ptys (/dev/pts/N)")
def test_a_probe_of_the_last_sim_pty_is_not_taken_for_the_next_one(tmp_path):
    first, path = _sim_pty(tmp_path, "sim://", "first.json")
    try:
        _keep_probe(path, tmp_path / "data")  # as `armctl probe --yes --port PATH` keeps it
    finally:
        _stop(first)
    second, path_now = _sim_pty(tmp_path, "sim://?fifo_frames=20", "second.json")  # on PATH again, mostly
    try:
        script = _tiny_job(tmp_path, 60)  # the first move's 2 s let 40 frames queue behind it
        done = subprocess.run([sys.executable, "-m", "armctl", "run", str(script), "--port", path_now, "--no-live"],
                              capture_output=True, text=True, timeout=40, env=_env(tmp_path), cwd=tmp_path)
    finally:
        _stop(second)
    stats = json.loads((tmp_path / "second.json").read_text())
    assert stats["dropped"] > 0  # the FIFO of 20 dropped what a belief of 200 sent
    # so the job is not `finished`: the FIFO size it rests on was never measured on this arm
    assert done.returncode == 1, (path, path_now, done.stdout, done.stderr)
    assert "finished, unproven" in done.stdout + done.stderr


# --- a second Ctrl-C -----------------------------------------------------------------------------
# The first Ctrl-C sends the abort sequence and waits for the arm to come to rest; a second one stops
# that wait.  The summary then said only what the first does — last line sent 18, last known
# executed 15, "resume with: … --from-line 16" — while the arm still ran lines 16-18 queued before
# the pause (sim --stats: they ran after armctl exited).  Pasting that command runs them twice, and
# nothing said the arm was still moving.

def _stdout_until(process, marker: str, within_s: float) -> str:
    """What ``process`` printed up to the line holding ``marker`` (a progress line: a line every
    2 s with --no-live), read within ``within_s``."""
    import select

    printed, deadline = "", time.monotonic() + within_s
    while time.monotonic() < deadline:
        ready, _, _ = select.select([process.stdout], [], [], 0.1)
        if ready:
            line = process.stdout.readline()
            assert line, "the run ended before printing " + repr(marker) + ":\n" + printed + process.stderr.read()
            printed += line
            if marker in line:
                return printed
    raise AssertionError(f"{marker!r} not printed within {within_s} s:\n{printed}")


LONG_MOVES = "G1 X210 Y0 Z250 A180 B0 C0 S1500 F1000\nG1 Z200\nG1 Z250\nG1 Z200\nG1 Z250\n"  # 3 s each


@pytest.mark.realtime
@pytest.mark.timeout(60)
def test_a_second_ctrl_c_says_the_arm_may_still_be_running(tmp_path):
    import signal
    import time

    script = tmp_path / "long.txt"
    script.write_text(LONG_MOVES)
    arm, path = _sim_pty(tmp_path, "sim://", "arm.json")
    try:
        run = subprocess.Popen([sys.executable, "-m", "armctl", "run", str(script), "--port", path, "--no-live"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env(tmp_path), cwd=tmp_path)
        # the second move running, the third queued (lead 2 s): seen in the run's progress line, not
        # guessed from the wall clock (a loaded machine once took the fixed 4.5 s this waited to start)
        printed = _stdout_until(run, "line sent 3", 30)
        run.send_signal(signal.SIGINT)
        time.sleep(0.5)
        run.send_signal(signal.SIGINT)
        out, err = run.communicate(timeout=20)
        out = printed + out
        time.sleep(6.5)  # what was queued runs out (two moves at most)
    finally:
        _stop(arm)
    assert run.returncode == 130, out + err
    assert "Traceback" not in err
    stats = json.loads((tmp_path / "arm.json").read_text())
    assert [outcome for *_, outcome in stats["executions"]].count("done") >= 3  # it ran on past the second Ctrl-C
    said = out + err
    assert "the wait for the arm to come to rest was cut short" in said and "may still be running" in said, said
    assert "once the arm is at rest: it may have run lines from 2 meanwhile, which that runs again" in out, out


# --- the arm time on a noisy line ------------------------------------------------------------------
# 301 tiny moves at 115200 baud on a line with 5 % noise and 5 % corrupted reports (`armctl sim --pty
# --url 'sim://?baud=115200&noise=0.05&corrupt=0.05&seed=3'`): "arm time: 3.0 s from the first frame to
# the arm at rest" for 3.56 s by the simulator's record — the arm at rest before its last frame had
# even landed.  The status rotation reads X every 270 ms: moves of 4 ms back and forth alias into a
# still reading, and the rest was dated from it.  In virtual time, seeds 1 and 6, with the
# speed_tolerance a probe through a pty measures (1.25): 3.375 s and 3.405 s for 3.629 s and 3.642 s.  Now the arm time is never before the last frame left the wire.


@pytest.mark.parametrize("seed", (1, 6))
def test_the_arm_time_never_ends_before_the_last_frame_landed(tmp_path, monkeypatch, seed):
    from click.testing import CliRunner

    from armctl.ui.cli import main
    from test_resume_exactly_once import _open_one_arm

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    (tmp_path / "armctl.toml").write_text("[connector]\nspeed_tolerance = 1.25\n")  # as probed through a pty
    monkeypatch.chdir(tmp_path)
    ports = _open_one_arm(monkeypatch)
    url = f"sim://?clock=virtual&baud=115200&noise=0.05&corrupt=0.05&seed={seed}"
    result = CliRunner().invoke(main, ["run", str(_tiny_job(tmp_path)), "--port", url, "--baud", "115200", "--json"])
    summary = json.loads(result.stdout.splitlines()[-1])
    assert summary["outcome"] == "finished", summary
    model = ports[url].model
    first_written_s = model.frames_received[0].arrival_s - 48 * 10 / 115200
    truth_s = model.execution_log[-1].end_s - first_written_s
    landed_s = model.frames_received[-1].arrival_s - first_written_s
    assert summary["arm_time_s"] >= landed_s - 0.0005, (summary["arm_time_s"], truth_s)  # (rounded to the ms)


# --- ... and the other way: two corrupted reports in one rotation ----------------------------------
# joint_routine.txt (16.5 s) on `sim://?clock=virtual&noise=0.05&corrupt=0.05`, seeds 1-20: the arm time
# said 21.3-23.0 s in 4 of 20 (seeds 2, 3, 15, 17; +29 % to +39 %), and seed 15 added "the arm kept
# working past the estimate … armctl waited until it stopped"; at 10 % each,
# seed 11 said 46.2 s for 16.9 s.  A corrupted report is a "blip" (not work) only while no other
# position or joints kind changed meanwhile (armctl/core/job_readings.py, "Blips"): two corrupted
# reports in one rotation pass for motion.  Not fixed here: the rule is the core's evidence of work.


def test_corrupted_reports_do_not_make_work_after_the_job(tmp_path, monkeypatch):
    from pathlib import Path

    from click.testing import CliRunner

    from armctl.ui.cli import main
    from test_resume_exactly_once import _open_one_arm

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.chdir(tmp_path)
    ports = _open_one_arm(monkeypatch)
    url = "sim://?clock=virtual&noise=0.05&corrupt=0.05&seed=15"
    script = Path(__file__).parent.parent / "scripts" / "joint_routine.txt"
    result = CliRunner().invoke(main, ["run", str(script), "--port", url, "--json"])
    summary = json.loads(result.stdout.splitlines()[-1])
    assert summary["outcome"] == "finished", summary
    model = ports[url].model
    truth_s = model.execution_log[-1].end_s - (model.frames_received[0].arrival_s - 0.05)
    assert not any("kept working" in message for message in summary["messages"]), summary["messages"]
    assert summary["arm_time_s"] <= truth_s + 0.6, (summary["arm_time_s"], truth_s)  # two rotations late at most


# --- the line rate through a pty -------------------------------------------------------------------
# `sim://?baud=115200` opened at 9600 is a line set wrong: the host reads noise, the arm hears
# nothing (README, `baud`).  Through `armctl sim --pty` the rate the program set on the pty was
# ignored: `armctl status --once --baud 115200` on the default 9600 arm read its status, and `run
# --baud 115200` paced 301 frames 12 times faster than the arm's line took them — 15.2 s of arm time
# for "estimated 3.2 s (+370.3 %)", the backlog hidden in the pty's buffer (a Ctrl-C's pause waits
# behind it), and a probe at that rate would keep 115200 for a 9600 arm.


@pytest.mark.realtime
@pytest.mark.timeout(60)
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux ptys (/dev/pts/N)")
def test_a_pty_set_to_another_rate_than_the_arms_is_a_line_set_wrong(tmp_path):
    arm, path = _sim_pty(tmp_path, "sim://", "arm.json")  # the document's 9600 baud
    try:
        def status(*baud):
            return subprocess.run([sys.executable, "-m", "armctl", "status", "--once", "--port", path, "--timeout", "2",
                                   *baud], capture_output=True, text=True, timeout=30, env=_env(tmp_path), cwd=tmp_path)
        wrong, right = status("--baud", "115200"), status()
        script = _tiny_job(tmp_path, 4)
        ran = subprocess.run([sys.executable, "-m", "armctl", "run", str(script), "--port", path, "--no-live",
                              "--baud", "115200"], capture_output=True, text=True, timeout=30, env=_env(tmp_path), cwd=tmp_path)
    finally:
        _stop(arm)
    assert right.returncode == 0 and "xyz=210.0,0.0,300.0" in right.stdout, right.stderr
    assert wrong.returncode == 1 and "is the baud rate right?" in wrong.stderr, wrong.stdout + wrong.stderr
    assert ran.returncode == 1 and "is the baud rate right?" in ran.stderr, ran.stdout + ran.stderr
    stats = json.loads((tmp_path / "arm.json").read_text())
    assert stats["frames"] == []  # the arm heard nothing it could frame


def test_a_pty_probed_again_replaces_the_records_of_the_ptys_before_it_on_its_path(tmp_path):
    """A pty's identity names when it was made, so each `armctl sim --pty` probed is another arm:
    the records of those that had its path before are gone for good, and are dropped."""
    from armctl.host import calibration

    def keep(arm):
        findings = [("fifo_frames", 200, "measured", "sure")]
        calibration.save(calibration.calibration_of("/dev/pts/7", arm, findings, "2026-11-28"), tmp_path)

    keep("device /dev/pts/7")  # a record written before a pty's identity named its making
    keep("device /dev/pts/7 pty made 2026-11-28T17:00:00.000000001Z")
    keep("device /dev/pts/70 pty made 2026-11-28T17:00:00.000000002Z")  # another path
    keep("usb 0403:6001 serial A1")
    assert len(calibration.stored(tmp_path)) == 3  # the pty of the first record replaced it
    keep("device /dev/pts/7 pty made 2026-11-28T17:05:00.000000003Z")
    assert [record.arm for record in calibration.stored(tmp_path)] == [
        "device /dev/pts/7 pty made 2026-11-28T17:05:00.000000003Z",
        "device /dev/pts/70 pty made 2026-11-28T17:00:00.000000002Z", "usb 0403:6001 serial A1"]
