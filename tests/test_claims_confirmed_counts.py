"""Issue 21 item 4: "frames confirmed by the arm's reports" counts only frames a report proves
*executed*.

A report on a later frame's path proves the frames before it left the FIFO — and a frame a full
FIFO dropped left it too (and, planned in a row, the arm running the frame after a dropped one
passes right along the dropped one's path: no sighting tells them apart).  So a frame gone from
the FIFO counts as confirmed by the reports only where the FIFO size is proven (probed, or a
simulator that holds the profile's) and no RESET CONNECTOR may have cleared it, or where the arm
at rest at the last target proves that frame ran; the others are counted apart ("gone from the
buffer, not seen running"), and they leave the job "finished, unproven".  Judged by the simulator's own record:
a 60-frame FIFO that the profile believes holds 200, ``--lead 6`` — frames are dropped, and no
frame the summary counts as seen by the reports is one of them.  Virtual time; the installed
command in a fresh process gives the same summary.
"""

from __future__ import annotations

import json
import re

import pytest
from click.testing import CliRunner

import armctl.core.streamer.ledger
from armctl.ui.cli import main
from armctl.sim.executor import DONE
from claims_common import fresh, raster
from test_resume_exactly_once import _open_one_arm

URL = "sim://?clock=virtual&fifo_frames=60"
COUNTS = r"^frames confirmed by the arm's reports: (\d+); by time only: (\d+)(?:; gone from the buffer, not seen running: (\d+))?$"


def _counts(stdout: str) -> tuple[int, int, int]:
    found = re.search(COUNTS, stdout, re.M)
    assert found, stdout
    return int(found[1]), int(found[2]), int(found[3] or 0)


@pytest.fixture
def claimed(monkeypatch):
    """The frames (their indexes) the streamer counts as seen by the arm's reports."""
    seen: list[int] = []
    real = armctl.core.streamer.ledger.Ledger.consume_one

    def consume_one(self, by_reports):
        head, before = self.pending[0], self.confirmed_by_reports
        real(self, by_reports)
        if self.confirmed_by_reports > before:
            seen.append(head.index)

    real_proven = armctl.core.streamer.ledger.Ledger.proven_run

    def proven_run(self, sent):  # a frame time counted, recounted as seen: the arm at rest at its target
        before = self.confirmed_by_reports
        real_proven(self, sent)
        if self.confirmed_by_reports > before:
            seen.append(sent.index)

    monkeypatch.setattr(armctl.core.streamer.ledger.Ledger, "consume_one", consume_one)
    monkeypatch.setattr(armctl.core.streamer.ledger.Ledger, "proven_run", proven_run)
    return seen


def test_no_frame_the_fifo_dropped_is_claimed_seen_by_the_reports(tmp_path, monkeypatch, claimed):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    (tmp_path / "job.txt").write_text(raster(400), encoding="utf-8")
    ports = _open_one_arm(monkeypatch)
    result = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--lead", "6", "--port", URL])
    arm = ports[URL].model
    assert arm.frames_dropped > 20  # the case: a FIFO smaller than the profile says, overrun
    executed = {e.index for e in arm.execution_log if e.outcome == DONE}
    dropped = set(arm.dropped_indexes)
    by_reports, by_time, unseen = _counts(result.stdout)
    assert by_reports == len(claimed)
    assert not dropped & set(claimed), sorted(dropped & set(claimed))  # (the job's frame k is the arm's k-th)
    assert set(claimed) <= executed
    assert by_reports + by_time + unseen == 400
    assert by_reports <= 400 - arm.frames_dropped
    assert "finished: the arm finished the job" not in result.stdout

    # the same run, through the installed command in a fresh process: the same counts, told as such
    again = fresh(["-m", "armctl", "run", "job.txt", "--no-live", "--lead", "6", "--port", URL], tmp_path)
    assert _counts(again.stdout) == (by_reports, by_time, unseen)
    assert unseen and "gone from the buffer, not seen running" in again.stdout
    assert again.returncode == 1 and "a frame it dropped would look the same" in again.stderr


def test_a_job_on_a_fifo_that_holds_it_counts_what_was_seen_and_ends_done(tmp_path, monkeypatch, claimed):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    (tmp_path / "job.txt").write_text(raster(200), encoding="utf-8")
    ports = _open_one_arm(monkeypatch)
    url = "sim://?clock=virtual"
    result = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--port", url])
    assert result.exit_code == 0 and result.stdout.splitlines()[-1] == "finished: the arm finished the job", result.output
    arm = ports[url].model
    assert arm.frames_dropped == 0
    by_reports, by_time, unseen = _counts(result.stdout)
    assert by_reports + by_time + unseen == 200 and by_reports == len(claimed) > 20
    assert set(claimed) <= {e.index for e in arm.execution_log if e.outcome == DONE}


def test_frames_a_reset_connector_cleared_are_not_claimed_executed(tmp_path):
    # H5: the script's RESET CONNECTOR acts at the head and clears the three moves queued behind
    # it (a 60 s lead writes them at once); time never confirms a frame it may have cleared.
    script = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F6000\nG1 Y120\nRESET CONNECTOR\nG1 Y-120\nG1 Z100\nG1 Z150\n"
    (tmp_path / "job.txt").write_text(script, encoding="utf-8")
    result = fresh(["-m", "armctl", "run", "job.txt", "--no-live", "--lead", "60", "--port", "sim://?clock=virtual"],
                   tmp_path)
    assert result.returncode == 1, (result.stdout, result.stderr)
    assert "last line known executed: 3" in result.stdout  # not 6: lines 4-6 were cleared
    assert re.search(r"^resume with: armctl run job.txt --from-line 4 ", result.stdout, re.M)


def test_a_single_move_at_rest_at_its_target_is_proven_run_even_after_time_counted_it(tmp_path):
    # A move's last sighting lets the time bound count it consumed before the arm has been still
    # long enough to prove its rest: on a FIFO whose size is not proven it ended "finished,
    # unproven", exit 1 ("1 frames were confirmed by time alone"), though the arm at rest at a
    # target it was not at before proves the move ran.  Found by a review through sim --tcp.
    url = "sim://?clock=virtual&fifo_frames=199"  # the simulator's FIFO below the profile's 200: not proven
    moved = fresh(["-m", "armctl", "move", "z=200", "--json", "--port", url], tmp_path)
    result = json.loads(moved.stdout.splitlines()[-1])
    assert (result["outcome"], result["exit_code"], moved.returncode) == ("finished", 0, 0), moved.stdout + moved.stderr
    assert (result["frames_by_reports"], result["frames_by_time"]) == (1, 0)
    # a repeated target proves nothing of the frames before the last: those stay time's, and unproven
    (tmp_path / "back.txt").write_text("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\n"
                                       + "".join(f"G1 Z{150 - 40 * (k % 2)}\nG1 Z150\n" for k in range(1, 4)))
    run = fresh(["-m", "armctl", "run", "back.txt", "--no-live", "--json", "--port", url], tmp_path)
    summary = json.loads(run.stdout.splitlines()[-1])
    assert summary["frames_by_time"] > 0 and summary["outcome"] == "finished, unproven", run.stdout
