"""The live view of ``armctl run``: a pure function of a ``RunView``.

Strategy: like ``status_panel``, rendering takes a snapshot and returns a rich renderable (or a
plain line for pipes), so tests compare text from a recording console.  Text that comes from
the user (script lines, the file name in the title) goes in as ``Text``, never as a markup
string: ``G1 X[#<x0>]`` is an expression, not a rich style tag.
"""

from __future__ import annotations

from rich.console import Group
from rich.panel import Panel
from rich.progress_bar import ProgressBar
from rich.table import Table
from rich.text import Text

from ..runner import RunView


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


def render_run(view: RunView, title: str) -> Panel:
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
    position = "—" if view.position_mm is None else "  ".join(f"{v:.1f}" for v in view.position_mm)
    facts.add_row("position X Y Z", position)
    facts.add_row("last line sent", _line(view.last_sent))
    facts.add_row("last line done", _line(view.last_done))
    return Panel(Group(frames, facts), title=Text(title), expand=False)


def progress_line(view: RunView) -> str:
    """A plain progress line for output that is not a terminal."""
    sent = view.last_sent.line if view.last_sent is not None else "-"
    done = view.last_done.line if view.last_done is not None else "-"
    return (
        f"[{_clock(view.elapsed_s)}] frames {view.frames_sent}/{view.total_frames} · line sent {sent} · "
        f"line done {done} · queue ≤{view.queued_frames_bound} frames {view.queued_s:.1f}s · ETA {_clock(view.eta_s)}"
    )
