"""The live views as text: ``render_status`` and ``render_run`` rendered to a recording
``Console(width=…, color_system=None)`` and compared line by line; ``status_line`` and
``progress_line`` (what a pipe gets instead).  Styles (stale kinds dimmed) are read from the
rendered segments, since a console without colours prints none.
"""

from __future__ import annotations

from rich.console import Console

from armctl.core.armstate import STALE_AFTER_S, ArmState
from armctl.core.protocol import (
    FileLengthStatus, FileStatus, JointsHighStatus, JointsLowStatus, PauseStatus, PositionStatus, RunPositionStatus,
    WorktableStatus, WristStatus,
)
from armctl.core.job import RunView
from armctl.script import compile_text
from armctl.ui.run_panel import progress_line, render_run
from armctl.ui.status_panel import LinkHealth, render_status, status_line

NOW = 10.0


def rendered(renderable, width: int) -> list[str]:
    console = Console(width=width, record=True, color_system=None)
    console.print(renderable)
    return console.export_text().splitlines()


def dim_texts(renderable, width: int) -> list[str]:
    console = Console(width=width, color_system=None)
    return [s.text.strip() for s in console.render(renderable, console.options) if s.style is not None and s.style.dim]


def known_state() -> ArmState:
    """Every kind seen 100 ms before NOW, except the SD file length: 5 s before (stale)."""
    state = ArmState()
    for frame in (PositionStatus(250.5, -120, 150), JointsLowStatus(10, 20, 30), JointsHighStatus(0, 90, -45),
                  WorktableStatus(1, 2, 3), PauseStatus(1, 1500), WristStatus(0, 90), FileStatus(3),
                  RunPositionStatus(50.0)):
        state.update(frame, NOW - 0.1)
    state.update(FileLengthStatus(200.0), NOW - 5.0)
    return state


HEALTH = LinkHealth("sim://?speed=4", 9600, 33.3, 1234, 7, 1)

STATUS_PANEL = """\
╭───────────────────────────────────────── armctl status ──────────────────────────────────────────╮
│ X Y Z mm      250.5  -120.0  150.0                                                               │
│ joints deg    10.00  20.00  30.00  0.00  90.00  -45.00                                           │
│ wrist w0 w1   0.00  90.00                                                                        │
│ worktable mm  1.0  2.0  3.0                                                                      │
│ gripper PWM   1500 µs                                                                            │
│ paused        yes                                                                                │
│ SD program    ━━━━━                25% (status 3)                                                │
│                                                                                                  │
│ status kinds (age)                                                                               │
│               joints     joints  worktable  pause and            SD file     SD file     SD run  │
│  position        1-3        4-6     origin        PWM   wrist     length      status   position  │
│    100 ms     100 ms     100 ms     100 ms     100 ms  100 ms    5000 ms      100 ms     100 ms  │
│ sim://?speed=4 @ 9600 baud · 33.3 status frames/s · 1234 bytes read · 7 skipped · 1 suspect      │
╰──────────────────────────────────────────────────────────────────────────────────────────────────╯"""

EMPTY_STATUS_PANEL = """\
╭───────────────────────────────────────── armctl status ──────────────────────────────────────────╮
│ X Y Z mm      —  —  —                                                                            │
│ joints deg    —  —  —  —  —  —                                                                   │
│ wrist w0 w1   —  —                                                                               │
│ worktable mm  —  —  —                                                                            │
│ gripper PWM   —                                                                                  │
│ paused        —                                                                                  │
│ SD program    —                                                                                  │
│                                                                                                  │
│ status kinds (age)                                                                               │
│               joints     joints  worktable  pause and            SD file     SD file     SD run  │
│  position        1-3        4-6     origin        PWM   wrist     length      status   position  │
│     never      never      never      never      never   never      never       never      never  │
│ loop:// @ 9600 baud · 0.0 status frames/s · 0 bytes read · 0 skipped · 0 suspect                 │
╰──────────────────────────────────────────────────────────────────────────────────────────────────╯"""


# --- armctl status ------------------------------------------------------------------------------


def test_status_panel_as_text():
    assert rendered(render_status(known_state(), HEALTH, NOW), width=100) == STATUS_PANEL.splitlines()


def test_status_panel_before_anything_was_heard():
    health = LinkHealth("loop://", 9600, 0.0, 0, 0, 0)
    assert rendered(render_status(ArmState(), health, NOW), width=100) == EMPTY_STATUS_PANEL.splitlines()


def test_status_panel_key_rows_at_a_narrow_width():
    text = "\n".join(rendered(render_status(known_state(), HEALTH, NOW), width=80))
    for row in ("X Y Z mm", "250.5  -120.0  150.0", "joints deg", "worktable mm", "gripper PWM   1500 µs",
                "paused        yes", "SD program", "25% (status 3)", "status kinds (age)", "5000 ms", "33.3 status frames/s",
                "skipped"):
        assert row in text, row
    assert max(len(line) for line in text.splitlines()) <= 80


def test_stale_and_unseen_kinds_are_dimmed_and_fresh_ones_are_not():
    assert dim_texts(render_status(known_state(), HEALTH, NOW), width=100) == ["5000 ms"]
    assert dim_texts(render_status(ArmState(), HEALTH, NOW), width=100) == ["never"] * 9
    # just inside and just outside the stale age
    state = known_state()
    assert len(dim_texts(render_status(state, HEALTH, NOW - 0.1 + STALE_AFTER_S - 0.001), width=100)) == 1
    assert len(dim_texts(render_status(state, HEALTH, NOW - 0.1 + STALE_AFTER_S + 0.001), width=100)) == 9


def test_status_line():
    assert status_line(known_state()) == (
        "xyz=250.5,-120.0,150.0 joints=10.00 20.00 30.00 0.00 90.00 -45.00 pwm=1500 paused run_position=50.0"
    )


def test_status_line_of_a_running_arm():
    state = ArmState()
    state.update(PauseStatus(0, 900), NOW)
    assert " pwm=900 running " in status_line(state)


def test_status_line_before_anything_was_heard_shows_dashes_not_none():
    line = status_line(ArmState())
    assert line.startswith("xyz=—,—,— joints=— — — — — —")
    assert "None" not in line


# --- armctl run ---------------------------------------------------------------------------------

STATEMENTS = list(compile_text(
    "G1 X250 Y-120 Z150 A180 B0 C0 S1000 F3000\n"
    "G1 Z60 ; down to 30 mm above the part, slowly and carefully please\n"
    "G4 P500\n",
    "job.txt",
))


def a_view(**changes) -> RunView:
    values = dict(total_frames=4, estimated_job_s=75.4, lead_s=2.0, capacity=190, total_lines=3, started_s=100.0, now_s=165.2,
                  frames_sent=1, last_sent=STATEMENTS[1], last_done=STATEMENTS[0], queued_frames_bound=1,
                  queued_s=1.3, remaining_motion_s=0.5, position_mm=(250.0, -120.0, 101.26))
    values.update(changes)
    return RunView(**values)


RUN_PANEL = """\
╭─────────────────────────────────── armctl run job.txt ───────────────────────────────────╮
│ frames     ━━━━━━━━━━                               1/4                                  │
│ lines      ━━━━━━━━━━━━━━━━━━━━━━━━━━╸              2/3                                  │
│ elapsed / ETA     1:05 / 0:02 left (estimate 1:15)                                       │
│ queue (estimate)  ≤ 1 frames (limit 190) · 1.3 s of motion ahead (next frame when ≤ 2 s) │
│ feed · state      100 % · running                                                        │
│ position X Y Z    250.0  -120.0  101.3                                                   │
│ last line sent    2  G1 Z60                                                              │
│ last line done    1  G1 X250 Y-120 Z150 A180 B0 C0 S1000 F3000                           │
╰──────────────────────────────────────────────────────────────────────────────────────────╯"""


def test_run_panel_as_text():
    assert rendered(render_run(a_view(), "armctl run job.txt"), width=100) == RUN_PANEL.splitlines()


def test_run_panel_shows_the_override_the_pause_state_and_the_keys():
    from armctl.ui.run_keys import FOOTER

    view = a_view(feed_percent=150, feed_clamped=True, pause_state="pausing", pause_label="pausing…")
    text = "\n".join(rendered(render_run(view, "armctl run job.txt", footer=FOOTER), width=120))
    assert "feed · state      150 % (held to the profile's speed limit) · pausing…" in text
    assert "keys: space/p pause/resume · s/q stop (as Ctrl-C) · +/= feed +10 % · - feed −10 %" in text


def test_run_panel_shows_the_statement_without_its_comment_and_cuts_long_ones():
    long = list(compile_text("G1 X250.125 Y-120.125 Z150.125 A180.125 B0.125 C0.125 S1000 F3000 U1.125 V1.125 ; c\n"))
    text = "\n".join(rendered(render_run(a_view(last_sent=long[0]), "t"), width=120))
    assert "│ last line sent    1  G1 X250.125 Y-120.125 Z150.125 A180.125 B0.125 …  " in text  # 48 characters
    assert "; c" not in text and "U1.125" not in text


def test_run_panel_shows_a_line_of_exactly_48_characters_whole():
    line = "G1 X250.12 Y-120.125 Z150.125 A180.125 B0.125 C0"
    assert len(line) == 48
    statement = list(compile_text("G1 X0 Y0 Z100 A0 B0 C0 S1000 F3000\n" + line + "\n"))[1]
    text = "\n".join(rendered(render_run(a_view(last_sent=statement), "t"), width=120))
    assert f"│ last line sent    2  {line}  " in text and "…" not in text


def test_run_panel_shows_expressions_and_brackets_as_written():
    statements = list(compile_text(
        "#<x0> = 200\nG1 X[#<x0>] Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X[#<x0> + [2 * 5]]\n",
        "job.txt",
    ))
    view = a_view(last_sent=statements[1], last_done=statements[0])
    text = "\n".join(rendered(render_run(view, "armctl run [red]job[/red].txt"), width=120))
    assert "last line sent    3  G1 X[#<x0> + [2 * 5]]" in text
    assert "last line done    2  G1 X[#<x0>] Y0 Z150 A180 B0 C0 S1000 F3000" in text
    assert "armctl run [red]job[/red].txt" in text


def test_run_panel_at_the_start():
    view = a_view(now_s=100.0, frames_sent=0, last_sent=None, last_done=None, queued_frames_bound=0, queued_s=0.0,
                  remaining_motion_s=75.4, position_mm=None)
    lines = rendered(render_run(view, "armctl run job.txt"), width=100)
    text = "\n".join(lines)
    for row in ("0/4", "elapsed / ETA     0:00 / 1:15 left (estimate 1:15)", "≤ 0 frames (limit 190)",
                "position X Y Z    —", "last line sent    —", "last line done    —"):
        assert row in text, row


def test_run_panel_at_the_end():
    view = a_view(now_s=176.0, frames_sent=4, last_sent=STATEMENTS[2], last_done=STATEMENTS[2], queued_frames_bound=0,
                  queued_s=0.0, remaining_motion_s=0.0)
    text = "\n".join(rendered(render_run(view, "armctl run job.txt"), width=100))
    assert "━" * 40 + " 4/4" in text
    assert "elapsed / ETA     1:16 / 0:00 left (estimate 1:15)" in text
    assert "last line sent    3  G4 P500" in text and "last line done    3  G4 P500" in text


def test_run_panel_shows_progress_by_line_too():
    text = "\n".join(rendered(render_run(a_view(), "armctl run job.txt"), width=100))
    assert "lines" in text or "line 2/3" in text


def test_progress_line():
    assert progress_line(a_view()) == (
        "[1:05] frames 1/4 · line sent 2 · line done 1 · queue ≤1 frames 1.3s · ETA 0:02"
    )
    assert progress_line(a_view(frames_sent=0, last_sent=None, last_done=None, now_s=100.0)) == (
        "[0:00] frames 0/4 · line sent - · line done - · queue ≤1 frames 1.3s · ETA 0:02"
    )
    assert progress_line(a_view(feed_percent=50, pause_state="paused", pause_label="paused")).endswith(
        "· ETA 0:02 · feed 50 % · paused")  # the ETA of what is unsent at half speed: 1.3 + 2 × 0.5 s
