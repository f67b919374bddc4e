"""The live view of ``armctl run``: a pure function of a ``RunView``.

Strategy: like ``status_panel``, rendering takes a snapshot and returns a rich renderable (or a
plain line for pipes), so tests compare text from a recording console.  Text that comes from
the user (script lines, the file name in the title) goes in as ``Text``, never as a markup
string: ``G1 X[#<x0>]`` is an expression, not a rich style tag.

The map (a top view of the job, path_map.py) is drawn when the caller passes the job's
``PathGrid``: the characters and their states are path_map's, only their styles are here.
"""

from __future__ import annotations

from rich.console import Group
from rich.panel import Panel
from rich.progress_bar import ProgressBar
from rich.table import Table
from rich.text import Text

from ..core.job import RunView
from .path_map import ARM, ARM_GLYPH as ARM_MARK, DONE, QUEUED, TODO, PathGrid

MAP_STYLES = {DONE: "green", QUEUED: "bold yellow", TODO: "dim", ARM: "bold red"}


def _clock(seconds: float) -> str:
    seconds = max(0, int(round(seconds)))
    return f"{seconds // 60}:{seconds % 60:02d}"


LINE_TEXT_CHARS = 48  # a script line is cut to this (ellipsis included), so the panel keeps its width


def _line(statement) -> Text:
    if statement is None:
        return Text("—")
    code = statement.span.text.split(";", 1)[0].strip()  # the statement, not its comment
    if len(code) > LINE_TEXT_CHARS:
        code = code[: LINE_TEXT_CHARS - 1] + "…"
    return Text(f"{statement.line}  {code}")


def render_map(grid: PathGrid, view: RunView) -> Text:
    """The map's rows, styled by state, then what the shapes and colours mean."""
    text = Text()
    for line in grid.rows(view.frames_sent, view.frames_known_done, view.position_mm):
        for char, state in line:
            text.append(char, MAP_STYLES.get(state))
        text.append("\n")
    (x0, x1), (y0, y1) = grid.x_mm, grid.y_mm
    text.append(f"X {x0:.0f}…{x1:.0f} → · Y {y0:.0f}…{y1:.0f} ↑ mm\n", "dim")
    text.append("done", MAP_STYLES[DONE])
    text.append(" · ")
    text.append("queued", MAP_STYLES[QUEUED])
    text.append(" (solid: written) · ")
    text.append("not sent", MAP_STYLES[TODO])
    text.append(" (dotted) · ")
    text.append(f"{ARM_MARK} arm", MAP_STYLES[ARM])
    if grid.frames < view.total_frames:
        text.append(f"\nthe map shows the first {grid.frames} of {view.total_frames} frames", "dim")
    return text


def _control(view: RunView) -> Text:
    """The feed override and the pause state (the arm's reports decide it)."""
    text = Text(f"{view.feed_percent} %")
    if view.feed_clamped:
        text.append(" (held to the profile's speed limit)", "yellow")
    text.append(" · ")
    text.append(view.pause_label, "bold yellow" if view.pause_state != "running" or view.pause_label != "running" else None)
    return text


def render_run(view: RunView, title: str, grid: PathGrid | None = None, footer: str | None = None) -> Panel:
    frames = Table.grid(padding=(0, 1))
    frames.add_column(width=10)
    frames.add_column()
    frames.add_column(justify="right")
    done = view.frames_sent / view.total_frames if view.total_frames else 1.0
    frames.add_row("frames", ProgressBar(total=1.0, completed=done, width=40), f"{view.frames_sent}/{view.total_frames}")
    if view.total_lines:
        line = view.last_sent.line if view.last_sent is not None else 0
        frames.add_row("lines", ProgressBar(total=1.0, completed=min(line / view.total_lines, 1.0), width=40),
                       f"{line}/{view.total_lines}")

    facts = Table.grid(padding=(0, 2))
    facts.add_column(style="bold")
    facts.add_column()
    facts.add_row("elapsed / ETA", f"{_clock(view.elapsed_s)} / {_clock(view.eta_s)} left (estimate {_clock(view.estimated_job_s)})")
    facts.add_row(
        "queue (estimate)",
        f"≤ {view.queued_frames_bound} frames (limit {view.capacity}) · {view.queued_s:.1f} s of motion ahead "
        f"(next frame when ≤ {view.lead_s:g} s)",
    )
    position = "—" if view.position_mm is None else "  ".join(f"{v:z.1f}" for v in view.position_mm)
    facts.add_row("feed · state", _control(view))
    facts.add_row("position X Y Z", position)
    facts.add_row("last line sent", _line(view.last_sent))
    facts.add_row("last line done", _line(view.last_done))
    if grid is not None:
        facts.add_row("path X/Y (top)", render_map(grid, view))
    parts = [frames, facts] + ([Text(footer, "dim")] if footer else [])
    return Panel(Group(*parts), title=Text(title), expand=False)


def progress_line(view: RunView) -> str:
    """A plain progress line for output that is not a terminal."""
    sent = view.last_sent.line if view.last_sent is not None else "-"
    done = view.last_done.line if view.last_done is not None else "-"
    control = "" if view.feed_percent == 100 else f" · feed {view.feed_percent} %"
    control += "" if view.pause_label == "running" else f" · {view.pause_label}"
    return (
        f"[{_clock(view.elapsed_s)}] frames {view.frames_sent}/{view.total_frames} · line sent {sent} · "
        f"line done {done} · queue ≤{view.queued_frames_bound} frames {view.queued_s:.1f}s · ETA {_clock(view.eta_s)}"
        f"{control}"
    )
