"""The run panel's map (issue 12 item 2): a top view of the job, rasterised once, recoloured by
progress.

The rasteriser (armctl/ui/path_map.py) is checked as text on hand-made paths, where every dot
can be counted; the panel with a real job's map is compared as exact text from a recording
console; a property test feeds any path and any position into the fixed grid; the installed
command is run on a pseudo-terminal (the panel only draws on a terminal) against
``sim://?clock=virtual``, so the job takes a fraction of a second of wall time, with every
wait bounded.
"""

from __future__ import annotations

import math
import os
import select
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rich.console import Console

from armctl.core.motion import MotionModel
from armctl.host.profile import load_profile
from armctl.core.job import RunView
from armctl.script import compile_text
from armctl.ui.path_map import (
    ARM, ARM_GLYPH, DONE, EMPTY, MAP_HEIGHT_ROWS, MAP_WIDTH_CHARS, QUEUED, TODO, job_grid, rasterise,
)
from armctl.ui.run_job import _Display
from armctl.ui.run_panel import MAP_STYLES, progress_line, render_run

ROOT = Path(__file__).resolve().parents[1]
ARMCTL = [sys.executable, "-m", "armctl"]
WAIT_S = 20  # bound of any one wait on a child process; a healthy run takes a fraction of it
ENV = {key: value for key, value in os.environ.items() if key not in ("ARMCTL_PORT", "NO_COLOR")}
MODEL = MotionModel(load_profile(None))
STATE_LETTERS = {EMPTY: " ", TODO: "t", QUEUED: "q", DONE: "d", ARM: "@"}

# A 10 mm square, one frame a side, anticlockwise from (0, 0): 12 × 12 dots of 10/12 mm.
SQUARE = [(0, [(0, 0), (10, 0)]), (1, [(10, 0), (10, 10)]), (2, [(10, 10), (0, 10)]), (3, [(0, 10), (0, 0)])]


def drawn(grid, sent, done, arm=None) -> list[str]:
    """Each row as its characters, then its states as letters."""
    return [f"{''.join(c for c, _ in row)}|{''.join(STATE_LETTERS[s] for _, s in row)}"
            for row in grid.rows(sent, done, arm)]


def test_a_square_before_during_and_after_the_job():
    grid = rasterise(SQUARE, frames=4, width_chars=6, height_rows=3)
    assert (grid.x_mm, grid.y_mm) == ((0.0, 10.0), (0.0, 10.0))
    # nothing sent: every side dotted (every other dot along the line), every character "not sent"
    assert drawn(grid, 0, 0) == ["⠍⠈⠈⠈⠈⢘|tttttt",
                                 "⠅    ⢐|t    t",
                                 "⠅⡀⡀⡀⡀⣐|tttttt"]
    # two sides written, the first known done; the arm halfway up the second
    assert drawn(grid, 2, 1, (10, 5)) == ["⠍⠈⠈⠈⠈⢸|tttttt",
                                          "⠅    ◉|t    @",
                                          "⢅⣀⣀⣀⣀⣸|tddddq"]
    # all written, two known done; the arm back at the start
    assert drawn(grid, 4, 2, (0, 0, 99)) == ["⡏⠉⠉⠉⠉⢹|qqqqqq",
                                             "⡇    ⢸|q    d",
                                             "◉⣀⣀⣀⣀⣸|@ddddd"]
    assert drawn(grid, 4, 4) == ["⡏⠉⠉⠉⠉⢹|dddddd",
                                 "⡇    ⢸|d    d",
                                 "⣇⣀⣀⣀⣀⣸|dddddd"]


def test_the_arm_is_placed_in_the_robot_frame_from_its_worktable_report():
    grid = rasterise(SQUARE, frames=4, width_chars=6, height_rows=3, origin_mm=(10.0, 10.0))
    # reported (0, 0) on a worktable whose origin is at robot (10, 10): the top right corner
    assert grid.text_rows(4, 4, (0.0, 0.0))[0].endswith(ARM_GLYPH)
    # off the map: on its edge, never outside the grid; not finite: not drawn
    assert grid.text_rows(4, 4, (-1e6, -10.0))[2].startswith(ARM_GLYPH)  # robot (-999990, 0)
    assert ARM_GLYPH not in "".join(grid.text_rows(4, 4, (math.nan, 0.0)))


def test_a_path_without_extent_in_x_and_y_has_no_map():
    assert rasterise([], frames=0) is None
    assert rasterise([(0, [(5, 5), (5.5, 5.5)])], frames=1) is None
    assert rasterise([(0, [(math.inf, 0), (math.nan, 3)])], frames=1) is None
    # only Z moves, or no motion at all: nothing to see from above
    for job in ("G1 X200 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 Z60\nG1 Z150\n", "G4 P500\nM3\n"):
        start = compile_start(job)
        assert job_grid(compile_text(job, "job.txt"), MODEL, start) is None, job


def compile_start(job):
    """A start pose at the job's first point, so the approach move adds no extent."""
    first = next(iter(compile_text(job, "job.txt")))
    if hasattr(first.command, "x_mm"):
        return MODEL.initial_pose().replace(cartesian=(first.command.x_mm, first.command.y_mm, first.command.z_mm,
                                                        180.0, 0.0, 0.0))
    return MODEL.initial_pose()


# --- a real job's map, from plot's sampling -------------------------------------------------------

JOB = "G1 X200 Y-30 Z150 A180 B0 C0 S1000 F3000\nG1 X260\nG300 X290 Y0 Z150 R30\nG301 X260 Y30 Z150\nG1 X200\nG4 P500\n"
STATEMENTS = list(compile_text(JOB, "job.txt"))


def job_view(**changes) -> RunView:
    values = dict(total_frames=6, estimated_job_s=20.0, lead_s=2.0, capacity=190, total_lines=6, started_s=100.0,
                  now_s=110.0, frames_sent=4, queued_frames_bound=2, last_sent=STATEMENTS[3], last_done=STATEMENTS[1],
                  queued_s=1.0, remaining_motion_s=3.0, position_mm=(285.0, -10.0, 150.0))
    values.update(changes)
    return RunView(**values)


RUN_PANEL_WITH_MAP = """\
╭─────────────────────────────────── armctl run job.txt ───────────────────────────────────╮
│ frames     ━━━━━━━━━━━━━━━━━━━━━━━━━━╸              4/6                                  │
│ lines      ━━━━━━━━━━━━━━━━━━━━━━━━━━╸              4/6                                  │
│ elapsed / ETA     0:10 / 0:04 left (estimate 0:20)                                       │
│ queue (estimate)  ≤ 2 frames (limit 190) · 1.0 s of motion ahead (next frame when ≤ 2 s) │
│ feed · state      100 % · running                                                        │
│ position X Y Z    285.0  -10.0  150.0                                                    │
│ last line sent    4  G301 X260 Y30 Z150                                                  │
│ last line done    2  G1 X260                                                             │
│ path X/Y (top)         ⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠐⠒⠒⠢⣀⡀                                         │
│                                                ⠈⠑⢄                                       │
│                                                   ⠣⡀                                     │
│                                                    ⢣                                     │
│                            ⡀                       ⠈⡆                                    │
│                           ⢰⠁                       ⢠⠃                                    │
│                          ⢠⠃                       ◉⡎                                     │
│                          ⡎                       ⢀⠜                                      │
│                         ⡜                       ⡠⠊                                       │
│                        ⠰⠥⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠤⠔⠊⠉                                         │
│                   X 181…309 → · Y -32…32 ↑ mm                                            │
│                   done · queued (solid: written) · not sent (dotted) · ◉ arm             │
╰──────────────────────────────────────────────────────────────────────────────────────────╯"""


def job_map():
    return job_grid(iter(STATEMENTS), MODEL, MODEL.initial_pose())


def rendered(renderable, width: int = 100) -> list[str]:
    console = Console(width=width, record=True, color_system=None)
    console.print(renderable)
    return console.export_text().splitlines()


def test_the_run_panel_shows_the_map_as_text():
    # the approach from pose 0 (210, 0) to the first point, the bottom line and the arc written
    # (solid), the top line not yet (dotted), the arm on the arc
    assert rendered(render_run(job_view(), "armctl run job.txt", job_map())) == RUN_PANEL_WITH_MAP.splitlines()


def test_the_map_is_coloured_by_progress():
    grid = job_map()
    states = {state for row in grid.rows(4, 2, (285.0, -10.0)) for _, state in row}
    assert states == {EMPTY, TODO, QUEUED, DONE, ARM}
    console = Console(width=100, color_system="standard")
    segments = list(console.render(render_run(job_view(), "t", grid), console.options))
    styled = {s.style for s in segments if s.text == ARM_GLYPH}
    assert styled and all(style == console.get_style(MAP_STYLES[ARM]) for style in styled)
    # the arc (frames 2-3, written, not known done) is queued, the bottom line (frame 1) done,
    # the top line (frame 4) not sent
    for char, state in (("⢣", QUEUED), ("⡆", QUEUED), ("⠥", DONE), ("⠐", TODO)):
        having = [s for s in segments if char in s.text]
        assert having and all(s.style == console.get_style(MAP_STYLES[state]) for s in having), char


def test_the_map_counts_frames_with_the_g300_of_an_arc():
    grid = job_map()
    assert grid.frames == 6  # every frame, the G300 and the still G4 included
    assert max(cell.last_ordinal for cell in grid.cells.values()) == 4  # G1 X200; the G4 draws nothing
    # the arc belongs to its G301 (frame 3), not to its G300 (frame 2)
    column, row = grid.cell_of(290.0, 0.0)
    assert grid.rows(3, 3)[row][column][1] == TODO  # the G300 written and done: the arc not yet sent
    assert grid.rows(4, 3)[row][column][1] == QUEUED
    assert grid.rows(4, 4)[row][column][1] == DONE


def test_a_huge_job_is_sampled_up_to_the_bound_and_the_panel_says_so():
    job = "G1 X200 Y0 Z150 A180 B0 C0 S1000 F3000\n" + "".join(f"G1 X{200 + k % 50} Y{k % 37}\n" for k in range(300))
    grid = job_grid(compile_text(job, "job.txt"), MODEL, MODEL.initial_pose(), max_frames=50)
    assert grid.frames == 50
    assert max(cell.last_ordinal for cell in grid.cells.values()) == 49
    text = "\n".join(rendered(render_run(job_view(total_frames=301), "t", grid), width=100))
    assert "the map shows the first 50 of 301 frames" in text


def test_the_run_panel_without_a_map_and_the_plain_line_are_unchanged():
    text = "\n".join(rendered(render_run(job_view(), "t")))
    assert "path X/Y" not in text and ARM_GLYPH not in text
    assert ARM_GLYPH not in progress_line(job_view()) and "⠐" not in progress_line(job_view())


# --- any path, any position ---------------------------------------------------------------------

coordinate = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.floats(-1000, 1000))
point = st.tuples(coordinate, coordinate)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(paths=st.lists(st.lists(point, min_size=1, max_size=8), max_size=6),
       arm=st.one_of(st.none(), st.tuples(coordinate, coordinate, coordinate)),
       width=st.integers(1, 12), height=st.integers(1, 5), sent=st.integers(0, 8), done=st.integers(0, 8),
       origin=point)
def test_any_path_and_any_position_fit_the_fixed_grid(paths, arm, width, height, sent, done, origin):
    polylines = list(enumerate(paths))
    origin = tuple(v if math.isfinite(v) else 0.0 for v in origin)
    grid = rasterise(polylines, frames=len(paths), width_chars=width, height_rows=height, origin_mm=origin)
    if grid is None:
        return
    rows = grid.rows(sent, min(done, sent), arm)
    assert len(rows) == height and all(len(row) == width for row in rows)
    assert all(len(char) == 1 for row in rows for char, _ in row)
    assert all(0 <= column < width and 0 <= row < height for column, row in grid.cells)


# --- the display and the installed command --------------------------------------------------------


@pytest.mark.parametrize("width, height, shown", [(100, 40, True), (70, 40, False), (100, 20, False)])
def test_the_display_draws_the_map_only_where_it_fits(width, height, shown):
    import io

    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=width, height=height, color_system=None,
                      legacy_windows=False)
    with _Display("armctl run job.txt", True, console=console, grid=job_map()) as display:
        display.update(job_view(outcome="finished"))
    assert ("path X/Y (top)" in out.getvalue()) is shown
    assert (ARM_GLYPH in out.getvalue()) is shown


def run_on_a_terminal(arguments, columns: int, lines: int) -> tuple[int, str]:
    """The installed command on a pseudo-terminal of columns × lines; (exit code, output)."""
    import fcntl
    import struct
    import termios

    master, slave = os.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", lines, columns, 0, 0))
    env = {**ENV, "TERM": "xterm-256color", "COLUMNS": str(columns), "LINES": str(lines)}
    try:
        process = subprocess.Popen([*ARMCTL, *arguments], stdin=slave, stdout=slave, stderr=slave, env=env, cwd=ROOT)
    finally:
        os.close(slave)
    data = b""
    try:
        deadline = time.monotonic() + WAIT_S
        while time.monotonic() < deadline:
            ready, _, _ = select.select([master], [], [], 0.1)
            if not ready:
                if process.poll() is not None:
                    break
                continue
            try:
                chunk = os.read(master, 65536)
            except OSError:  # EIO: the child closed the terminal
                break
            if not chunk:
                break
            data += chunk
        code = process.wait(timeout=WAIT_S)
    finally:
        process.kill()
        os.close(master)
    return code, data.decode("utf-8", "replace")


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a POSIX pseudo-terminal")
def test_armctl_run_on_a_terminal_shows_the_map_and_hides_it_when_narrow_or_not_live():
    arguments = ["run", "scripts/draw_square_circle.txt", "--port", "sim://?clock=virtual"]
    code, text = run_on_a_terminal(arguments, 120, 40)
    assert code == 0, text[-800:]
    assert "path X/Y (top)" in text and ARM_GLYPH in text and "finished: the arm finished the job" in text
    code, text = run_on_a_terminal(arguments, 70, 40)
    assert code == 0, text[-800:]
    assert "last line sent" in text and "path X/Y" not in text
    code, text = run_on_a_terminal([*arguments, "--no-live"], 120, 40)
    assert code == 0, text[-800:]
    assert "frames 16/16" in text or "finished: the arm finished the job" in text
    assert "path X/Y" not in text and ARM_GLYPH not in text and "⣀" not in text


def test_armctl_run_in_process_without_a_terminal_draws_no_map():
    from click.testing import CliRunner

    from armctl.ui.cli import main

    result = CliRunner().invoke(main, ["run", str(ROOT / "scripts" / "draw_square_circle.txt"),
                                       "--port", "sim://?clock=virtual"], env={"ARMCTL_PORT": None})
    assert result.exit_code == 0, result.output
    assert "finished: the arm finished the job" in result.output
    assert "path X/Y" not in result.output and ARM_GLYPH not in result.output
