"""Review 7: the live panel of ``armctl run`` wrote about 880 KB to the terminal for a 16 s job.

Measured on a pseudo-terminal of 120 × 40 (``script``, the installed command, ``sim://``): 1,201,925
bytes for ``scripts/joint_routine.txt`` (16.5 s of arm time, 19.7 s wall): 347 panels of some
3.4 KB, each drawn whole — rich's Live redrew the unchanged panel 10 times a second on its own
thread, and the job's updates redrew it up to 10 times a second more.  A person needs the lines
that changed, a few times a second.

Here the job runs in virtual time through the Python API with ``armctl run``'s observer and the
panel on a recording terminal, its clock the job's (``run_job.time`` follows the view's model
time): no wall clock is measured, and the bytes per second of the job are what a terminal would get.
"""

from __future__ import annotations

import io
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from rich.console import Console

ROOT = Path(__file__).resolve().parents[1]
JOB = ROOT / "scripts" / "joint_routine.txt"  # 16.5 s of arm time; its map fits 120 × 40
# The budget: the first panel once (3.4 KB at 120 × 40, its map included), then at most 4 redraws
# a second of the lines that change while the arm moves — frames, elapsed / ETA, queue, position,
# the two last lines: 6 lines of ≤ 120 columns, ~150 bytes each with their styles: ≤ 3.6 KB a
# second.  Before: 10.9 KB a second here (each redraw the whole panel), 61 KB a second on a terminal.
BYTES_PER_JOB_S = 4000
FIRST_PANEL_BYTES = 4000


class _ModelTime:
    """``run_job``'s ``time``: the job's model clock (the last view's ``now_s``)."""

    now = 0.0

    def monotonic(self) -> float:
        return self.now


def _panel_output(monkeypatch, script: Path, width: int = 120, height: int = 40) -> tuple[str, object, object]:
    """What the panel wrote for ``script``, the job's last view and its map."""
    from armctl import Arm
    from armctl.core.motion import MotionModel
    from armctl.ui import run_job

    clock = _ModelTime()
    monkeypatch.setattr(run_job, "time", clock)
    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=width, height=height, color_system="256",
                      legacy_windows=False)

    class Observer(run_job._RunObserver):
        def update(self, view) -> None:
            clock.now = view.now_s
            super().update(view)

    options = run_job.JobOptions(str(script), "sim://?clock=virtual", None, 0.5, 1, False, None, True, "pause", None, 3.0)
    with Arm.open("sim://?clock=virtual") as arm:
        watch = Observer(options, MotionModel(arm.profile), None)
        watch.display = run_job._Display(f"armctl run {script.name}", True, console=console)
        try:
            result = arm.run(script, observer=watch)
        finally:
            watch.display.__exit__(None, None, None)
    assert result.outcome == "finished", result
    return out.getvalue(), watch.view, watch.display.grid


def test_the_live_panel_writes_only_what_changes_a_few_times_a_second(monkeypatch):
    text, view, _ = _panel_output(monkeypatch, JOB)
    job_s = view.now_s - view.started_s
    written = len(text.encode())
    assert job_s > 15
    assert "path X/Y (top)" in text  # the map was drawn
    assert written <= FIRST_PANEL_BYTES + BYTES_PER_JOB_S * job_s, f"{written} bytes for {job_s:.1f} s of the job"


def test_the_terminal_shows_the_whole_last_panel_at_the_end(monkeypatch):
    """What the terminal shows at the end (tests/test_ctrl_c.py's emulator of the controls used)
    is the panel of the job's last view, drawn afresh: nothing of it lost or left stale."""
    from test_ctrl_c import screen

    from armctl.ui.run_panel import render_run

    text, view, grid = _panel_output(monkeypatch, JOB)
    shown = [line for line in screen(re.sub(r"\x1b\[[0-9;]*m", "", text), width=120) if line]  # (colours: the emulator's regex takes no ';')
    assert shown[0].startswith("╭") and shown[-1].startswith("╰"), "\n".join(shown)
    assert any("frames" in line and f"{view.total_frames}/{view.total_frames}" in line for line in shown), "\n".join(shown)
    assert "path X/Y (top)" in "\n".join(shown)
    fresh = io.StringIO()
    Console(file=fresh, width=120, height=40, color_system=None, legacy_windows=False).print(
        render_run(view, f"armctl run {JOB.name}", grid))
    assert shown == [line.rstrip() for line in fresh.getvalue().splitlines() if line.strip()]


@pytest.mark.realtime
@pytest.mark.skipif(shutil.which("tmux") is None, reason="needs tmux")
def test_a_message_the_terminal_wraps_leaves_no_remnant_in_the_panel():
    """On a real terminal 110 columns wide, Ctrl-C's note (some 130 characters, soft-wrapped: the
    terminal wraps it) is printed above the panel: its second row once kept the rest of the
    panel's frames line beside it ('me to rest … ━━━━ 13/14 │'), as no line written erased it."""
    from test_ctrl_c import ENV, ROOT as REPO, WAIT_S, _wait_for_pane

    socket_name = f"armctl-test-wrap-{os.getpid()}"
    tmux = ["tmux", "-L", socket_name]
    command = f"{sys.executable} -m armctl run scripts/pick_and_place.txt --port 'sim://?speed=4'; echo EXIT=$?; sleep 60"
    subprocess.run([*tmux, "new-session", "-d", "-s", "t", "-x", "110", "-y", "45", command], cwd=REPO,
                   env={**ENV, "TERM": "xterm-256color"}, check=True, timeout=WAIT_S)
    try:
        _wait_for_pane(tmux, "last line sent    1")  # the panel is up and a frame went out
        subprocess.run([*tmux, "send-keys", "-t", "t", "C-c"], check=True, timeout=WAIT_S)
        pane = _wait_for_pane(tmux, "EXIT=")
    finally:
        subprocess.run([*tmux, "kill-server"], timeout=WAIT_S, capture_output=True)
    assert "EXIT=130" in pane, pane
    rows = pane.splitlines()
    note = next(row for row, text in enumerate(rows) if text.startswith("armctl: interrupted: no more frames"))
    assert len(rows[note]) == 110 and "to rest …" in rows[note + 1], pane  # the terminal wrapped it
    assert "│" not in rows[note + 1] and "━" not in rows[note + 1], pane  # and nothing of the panel beside it
    assert rows[note + 2].startswith("╭"), pane
