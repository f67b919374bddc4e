"""Global ``-v``/``-q``, and the streamer's reasons as data that ``-v`` logs.

The streamer's ``write_reason`` and ``bound_evidence`` are tested on values (pure core); the
log and the quiet output through ``armctl run`` on ``sim://?clock=virtual`` (a 31 s job in
model time, well under a second of wall time), in-process and in a fresh process.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

import armctl.core.streamer as streamer_module
from armctl.ui.cli import main
from armctl.core.motion import MotionModel
from armctl.host.profile import find_config, load_profile
from armctl.core.protocol import Delay, LinearMove, MCode, PauseStatus
from armctl.core.streamer import CAPACITY_MARGIN_FRAMES, Evidence, Streamer, WaitReason

MODEL = MotionModel(load_profile())
JOB = str(Path(__file__).parent.parent / "scripts" / "pick_and_place.txt")
SIM = "sim://?clock=virtual"
SUMMARY_PREFIXES = ("frames: ", "time: ", "arm time: ", "frames confirmed by the arm's reports: ", "finished: ")
WARNING_SCRIPT = "G1 X450 Y0 Z150 A180 B-90 C0 S1500 F3000\n"  # L103 against the illustrative workspace (the arm still reaches it)


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    assert find_config(tmp_path)[0] is None, "an armctl.toml above the temporary directory"


def line(x, y, z, speed=6000.0):
    return LinearMove(x, y, z, 180.0, 0.0, 0.0, 1500.0, speed)


# --- the streamer's reasons, as data --------------------------------------------------------------


def test_the_streamer_stays_pure():
    for path in sorted(Path(streamer_module.__file__).parent.glob("*.py")):  # every module of the package
        source = path.read_text(encoding="utf-8")
        tree = ast.parse(source)
        imported = {alias.name.split(".")[0] for node in ast.walk(tree) if isinstance(node, (ast.Import, ast.ImportFrom))
                    for alias in node.names} | {node.module.split(".")[0] for node in ast.walk(tree)
                                                if isinstance(node, ast.ImportFrom) and node.module}
        assert not imported & {"logging", "time", "serial", "click", "rich", "threading"}, path.name
        assert "print(" not in source, path.name


def test_write_reason_names_the_wire_the_lead_and_the_capacity():
    s = Streamer(MODEL, MODEL.initial_pose(), lead_s=2.0)
    assert s.next_write_time(0.0, line(250.0, 0.0, 150.0)) == 0.0 and s.write_reason is WaitReason.READY
    s.wrote(line(250.0, 0.0, 150.0), 0.0)  # 1.55 s of motion
    assert s.next_write_time(0.0, line(250.0, 120.0, 150.0)) > 0.0 and s.write_reason is WaitReason.WIRE
    s.wrote(line(250.0, 120.0, 150.0), s.wire_free_s)  # 1.2 s waits behind it
    assert s.next_write_time(s.wire_free_s, line(250.0, 0.0, 150.0)) > s.wire_free_s
    assert s.write_reason is WaitReason.LEAD  # 1.2 s more would make 2.4 s waiting

    full = Streamer(MODEL, MODEL.initial_pose())
    for k in range(200 - CAPACITY_MARGIN_FRAMES):
        full.wrote(MCode(k), full.wire_free_s)
    assert full.next_write_time(full.wire_free_s) is None and full.write_reason is WaitReason.CAPACITY


def test_bound_evidence_names_time_and_at_rest():
    s = Streamer(MODEL, MODEL.initial_pose())
    s.wrote(Delay(1000.0), 0.0)
    s.wrote(Delay(1000.0), s.wire_free_s)
    assert s.bound_evidence is None
    s.receive_status(PauseStatus(0, 1500), 3.0)  # a running arm, 3 s on: the first delay is surely done
    assert s.consumed_lower_bound == 1 and s.bound_evidence is Evidence.TIME
    s.confirm_all_done()
    assert s.all_consumed and s.bound_evidence is Evidence.AT_REST


# --- -v ------------------------------------------------------------------------------------------


def assert_explains_pacing(stderr: str) -> list[str]:
    story = [text for text in stderr.splitlines() if text.startswith("armctl: t=")]
    assert any("waits for the lead" in text for text in story), stderr
    assert any("evidence (" in text for text in story), stderr
    # a line only when the reason changes: never the same reason twice in a row
    waits = [text.split(" waits for ")[1].split(":")[0] for text in story if " waits for " in text]
    assert all(a != b for a, b in zip(waits, waits[1:])), waits
    assert len(story) < 20, story  # a story, not one line per frame
    return story


def test_verbose_run_explains_the_pacing_in_process():
    result = CliRunner().invoke(main, ["-v", "run", JOB, "--port", SIM, "--no-live"])
    assert result.exit_code == 0, result.output
    assert_explains_pacing(result.stderr)
    assert "armctl: t=" not in result.stdout  # the log is on stderr


def test_verbose_run_explains_the_pacing_in_a_fresh_process(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    done = subprocess.run([sys.executable, "-m", "armctl", "-v", "run", JOB, "--port", SIM, "--no-live"],
                          capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert_explains_pacing(done.stderr)


def test_verbose_run_names_the_wire_and_the_fifo_capacity_on_a_job_of_short_moves(tmp_path):
    """400 moves of 2 mm (0.1 s each, twice a frame's time on the wire): the line leads at first,
    then the lead, and the FIFO fills while the evidence cannot tell the repeated targets apart."""
    moves = "".join(f"G1 X{212 if k % 2 == 0 else 210} F1200\n" for k in range(400))
    (tmp_path / "short.txt").write_text("G1 X210 Y0 Z300 A180 B0 C0 S1500 F1200\n" + moves, encoding="utf-8")
    result = CliRunner().invoke(main, ["-v", "run", "short.txt", "--port", SIM, "--no-live"])
    assert result.exit_code == 0, result.output
    story = [text for text in result.stderr.splitlines() if text.startswith("armctl: t=")]
    assert any("waits for the wire: the last 20 frames" in text for text in story), story
    assert any("waits for the FIFO's capacity: 196 frames" in text for text in story), story
    assert len(story) < 20, story


def test_without_v_nothing_is_logged_even_after_a_v_run_in_the_same_process():
    CliRunner().invoke(main, ["-v", "run", JOB, "--port", SIM, "--no-live"])
    result = CliRunner().invoke(main, ["run", JOB, "--port", SIM, "--no-live"])
    assert result.exit_code == 0, result.output
    assert "waits for" not in result.stderr and "evidence (" not in result.stderr


# --- -q ------------------------------------------------------------------------------------------


def test_quiet_run_prints_only_the_summary(tmp_path):
    (tmp_path / "job.txt").write_text(WARNING_SCRIPT, encoding="utf-8")
    for job in (JOB, "job.txt"):
        result = CliRunner().invoke(main, ["-q", "run", job, "--port", SIM, "--no-live"])
        assert result.exit_code == 0, result.output
        assert result.stderr == ""  # no banner, no warning (L103), no log
        lines = result.stdout.splitlines()
        assert [text.startswith(prefix) for text, prefix in zip(lines, SUMMARY_PREFIXES)] == [True] * 5, lines
        assert len(lines) == 5


def test_quiet_run_in_a_fresh_process(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    done = subprocess.run([sys.executable, "-m", "armctl", "-q", "run", JOB, "--port", SIM, "--no-live"],
                          capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert [text.split(":")[0] for text in done.stdout.splitlines()] == ["frames", "time", "arm time",
                                                                             "frames confirmed by the arm's reports", "finished"]


def test_quiet_still_prints_errors(tmp_path):
    (tmp_path / "bad.txt").write_text("G1 X500\n", encoding="utf-8")  # E004: no earlier move set A B C S
    result = CliRunner().invoke(main, ["-q", "run", "bad.txt", "--port", SIM, "--no-live"])
    assert result.exit_code == 1 and "E004" in result.stderr and result.stdout == ""


def test_quiet_lint_lists_errors_not_warnings(tmp_path):
    (tmp_path / "warn.txt").write_text(WARNING_SCRIPT, encoding="utf-8")
    (tmp_path / "bad.txt").write_text("G1 X500\n", encoding="utf-8")
    result = CliRunner().invoke(main, ["-q", "lint", "warn.txt", "bad.txt"])
    assert result.exit_code == 1
    assert "E004" in result.stdout and "L103" not in result.stdout
    assert "1 error" in result.stdout and "1 warning" in result.stdout  # the summary counts both
    loud = CliRunner().invoke(main, ["lint", "warn.txt"])
    assert "L103" in loud.stdout


def test_v_and_q_together_is_a_usage_error():
    result = CliRunner().invoke(main, ["-v", "-q", "ports"])
    assert result.exit_code == 2 and "choose -v or -q" in result.stderr
