"""A log is resumed once: a second ``--resume`` of the same log would run again every line the
first resume ran.  Found by the crash review: through ``armctl sim --pty``, a job killed after 2
frames, ``--resume j1`` finished it, then ``--resume j1`` again said "resuming at line 3" and
the arm ran lines 3 and 4 twice — the arm stood where j1's last frame leaves it, which is all a
log can check.  Now a resume marks the log it continues, durably, before its first frame goes
(a sealed ``resumed`` record: where it continued and the log it wrote), and a marked log is
refused (exit 2, nothing sent), naming the log to resume instead.

One simulated arm across the runs (tests/test_resume_exactly_once.py's ``_open_one_arm``),
virtual time; and one fresh-process case through the installed command.
"""

from __future__ import annotations

import io

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from test_resume_exactly_once import _job, _open_one_arm, _stop_after

pytestmark = pytest.mark.timeout(60)

URL = "sim://?clock=virtual"
ARMCTL = Path(sys.executable).with_name("armctl")  # the installed command


def _invoke(*args):
    return CliRunner().invoke(main, list(args), env={"ARMCTL_PORT": None})


def _stopped_job(tmp_path, monkeypatch, frames: int) -> dict:
    """``armctl run job.txt --log j1.log`` on one simulated arm, stopped (Ctrl-C) once ``frames``
    frames were sent; the ports opened (one arm, kept for the runs after)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "job.txt").write_text(_job(), encoding="utf-8")
    ports = _open_one_arm(monkeypatch)
    _stop_after(monkeypatch, frames)
    first = _invoke("run", "job.txt", "--no-live", "--port", URL, "--log", "j1.log")
    assert first.exit_code == 130, first.output
    return ports


def _run_then_resume(tmp_path, monkeypatch, second_log: bool = True):
    """The job stopped after 14 frames (--log j1), then resumed to its end (--log j2, or none);
    the arm is then moved back to where j1 left it.  The ports opened (one arm)."""
    ports = _stopped_job(tmp_path, monkeypatch, 14)
    where = json.loads(_invoke("status", "--json", "--port", URL).stdout)
    resumed = _invoke("run", "job.txt", "--no-live", "--port", URL, "--resume", "j1.log",
                      *(("--log", "j2.log") if second_log else ()))
    assert resumed.exit_code == 0 and "resuming job.txt at line" in resumed.output, resumed.output
    assert "moved since" not in resumed.output  # the arm stood where j1 left it
    back = tmp_path / "back.txt"  # the arm back where j1 left it, as a person might jog it
    back.write_text(f"G1 X{where['x']} Y{where['y']} Z{where['z']} A180 B0 C0 S1500 F3000\n", encoding="utf-8")
    moved = _invoke("run", str(back), "--no-live", "--port", URL)
    assert moved.exit_code == 0, moved.output
    return ports


@pytest.mark.parametrize("second_log", [True, False], ids=["with --log", "without --log"])
def test_a_log_resumed_once_is_refused_the_second_time(second_log, tmp_path, monkeypatch):
    ports = _run_then_resume(tmp_path, monkeypatch, second_log)
    arm = ports[URL].model
    ran = len(arm.execution_log)
    again = _invoke("run", "job.txt", "--no-live", "--port", URL, "--resume", "j1.log")
    assert again.exit_code == 2, again.output
    assert "was resumed already" in again.output, again.output
    assert ("resume j2.log instead" in again.output) if second_log else ("--from-line" in again.output)
    assert len(arm.execution_log) == ran  # nothing sent
    if second_log:  # the log the first resume wrote is the one to go on from: it says nothing is left
        last = _invoke("run", "job.txt", "--no-live", "--port", URL, "--resume", "j2.log")
        assert "resumed already" not in last.output, last.output
        assert len(arm.execution_log) == ran


def test_the_installed_command_refuses_a_log_resumed_already(tmp_path, monkeypatch):
    # the marked log, then the installed command in a fresh process: refused before any port opens
    _run_then_resume(tmp_path, monkeypatch)
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    again = subprocess.run([str(ARMCTL), "run", "job.txt", "--no-live", "--port", URL, "--resume", "j1.log"],
                           cwd=tmp_path, env=env, capture_output=True, text=True, timeout=50)
    assert again.returncode == 2, again.stdout + again.stderr
    assert "j1.log: it was resumed already, at line" in again.stderr and "resume j2.log instead" in again.stderr
    assert "Traceback" not in again.stderr and "using the built-in simulator" not in again.stderr, again.stderr


def test_the_mark_keeps_the_intact_prefix_and_follows_a_whole_line(tmp_path):
    # a torn last line (the crash's cut: its frame never went) is cut off before the mark, so the
    # mark follows a whole line and the log stays readable; a log with no whole line is not marked
    from armctl.core.joblog import job_record, read_resume_lines, seal
    from armctl.host.jobflow import mark_resumed

    data = b"G1 X1\n"
    whole = seal(job_record("a.txt", data, 1, 2.0), 0) + "\n"
    log = tmp_path / "j.log"
    log.write_text(whole + '{"t": 1.0, "dir": "tx", "he')
    mark_resumed(str(log), 1, None)
    text = log.read_text()
    assert text.startswith(whole) and text.count("\n") == 2 and '"dir": "resumed"' in text.splitlines()[1]
    with pytest.raises(Exception, match="resumed already, at line 1"):
        read_resume_lines(io.StringIO(text), "a.txt", data)
    bare = tmp_path / "torn.log"
    bare.write_text('{"t": 0.0, "dir": "jo')
    with pytest.raises(OSError):
        mark_resumed(str(bare), 1, None)
    assert bare.read_text() == '{"t": 0.0, "dir": "jo'


def test_a_resume_from_where_the_arm_was_moved_to_says_so(tmp_path, monkeypatch):
    # Found by the serve review: every frame the log records proven done, the arm then moved
    # elsewhere (a move, a jog, another job), and --resume said only "resuming at line N: the log
    # and the arm's report prove every line before it ran" and went on from there.  No line runs
    # twice, so it still goes on (README: every frame written proven done, it continues after it),
    # but the person resuming is told the next move starts from where the arm stands.
    _stopped_job(tmp_path, monkeypatch, 14)
    in_place = json.loads(_invoke("status", "--json", "--port", URL).stdout)
    elsewhere = tmp_path / "elsewhere.txt"
    elsewhere.write_text("G1 X230 Y-30 Z200 A180 B0 C0 S1500 F3000\n", encoding="utf-8")
    assert _invoke("run", str(elsewhere), "--no-live", "--port", URL).exit_code == 0
    resumed = _invoke("run", "job.txt", "--no-live", "--port", URL, "--resume", "j1.log")
    assert resumed.exit_code == 0, resumed.output
    assert "(moved since?): line 15 starts from where it stands" in resumed.output, resumed.output
    assert "resuming job.txt at line 15" in resumed.output
    assert in_place["x"] != 230.0  # (the arm had stood elsewhere: the note is about this move)


def test_nothing_to_resume_says_the_arm_is_still_paused(tmp_path, monkeypatch):
    # Found by the crash review: a job stopped (Ctrl-C) once every frame was written ran them all
    # and the abort's pause paused the arm; --resume said only "nothing to resume" and left the
    # arm paused without a word, so the next move seemed not to work.
    _stopped_job(tmp_path, monkeypatch, 31)
    again = _invoke("run", "job.txt", "--no-live", "--port", URL, "--resume", "j1.log")
    assert again.exit_code == 0 and "nothing to resume" in again.output, again.output
    assert "the arm is paused, as the stop left it" in again.output, again.output
    assert json.loads(_invoke("status", "--json", "--port", URL).stdout)["paused"] is True  # (said, not changed)
