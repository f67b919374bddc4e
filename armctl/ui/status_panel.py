"""The live status view: an ``ArmState`` and link health as a rich panel or a plain line.

Strategy: rendering is a pure function of a state snapshot and ``now``, so tests render it to
a recording ``Console(width=…, color_system=None)`` and compare text; the refresh loop lives in
the CLI edge.
"""

from __future__ import annotations

from dataclasses import dataclass

from rich.console import Group
from rich.panel import Panel
from rich.progress_bar import ProgressBar
from rich.table import Table
from rich.text import Text

from ..core.armstate import STALE_AFTER_S, ArmState
from ..core.protocol import STATUS_KINDS, STATUS_ROTATION


@dataclass(frozen=True)
class LinkHealth:
    url: str
    baud: int
    frames_per_s: float
    bytes_received: int
    bytes_skipped: int
    suspect_frames: int


def _num(value, digits: int = 1) -> str:
    return "—" if value is None else f"{value:.{digits}f}"


def render_status(state: ArmState, health: LinkHealth, now: float) -> Panel:
    pose = Table.grid(padding=(0, 2))
    pose.add_column(style="bold")
    pose.add_column()
    pose.add_row("X Y Z mm", "  ".join(_num(v) for v in (state.x_mm, state.y_mm, state.z_mm)))
    pose.add_row("joints deg", "  ".join(_num(v, 2) for v in state.joints_deg))
    pose.add_row("wrist w0 w1", "  ".join(_num(v, 2) for v in (state.w0_deg, state.w1_deg)))
    pose.add_row("worktable mm", "  ".join(_num(v) for v in state.worktable_mm))
    pose.add_row("gripper PWM", "—" if state.pwm_us is None else f"{state.pwm_us} µs")
    pose.add_row("paused", "—" if state.paused is None else ("yes" if state.paused else "no"))
    pose.add_row("SD program", _program_row(state))

    kinds = Table(title="status kinds (age)", title_justify="left", box=None, padding=(0, 1))
    for kind in STATUS_ROTATION:  # (as wide as an age under a second: the columns hold still as the ages change)
        kinds.add_column(STATUS_KINDS[kind].NAME, justify="right", min_width=len("999 ms"))
    cells = []
    for kind in STATUS_ROTATION:
        age = state.age(kind, now)
        text = "never" if age is None else f"{age * 1000:.0f} ms"
        stale = age is None or age > STALE_AFTER_S
        cells.append(Text(text, style="dim" if stale else ""))
    kinds.add_row(*cells)

    link = Text(
        f"{health.url} @ {health.baud} baud · {health.frames_per_s:.1f} status frames/s · "
        f"{health.bytes_received} bytes read · {health.bytes_skipped} skipped · {health.suspect_frames} suspect"
    )
    return Panel(Group(pose, Text(""), kinds, link), title="armctl status", expand=False)


def _program_row(state: ArmState):
    if not state.file_length or state.run_position is None:
        return "—"
    fraction = max(0.0, min(1.0, state.run_position / state.file_length))
    bar = Table.grid(padding=(0, 1))
    bar.add_row(ProgressBar(total=1.0, completed=fraction, width=20), f"{fraction:.0%} (status {state.file_status})")
    return bar


def status_line(state: ArmState) -> str:
    """One plain line for a terminal that is not one (a pipe, a log file)."""
    joints = " ".join(_num(v, 2) for v in state.joints_deg)
    paused = "—" if state.paused is None else ("paused" if state.paused else "running")
    pwm = "—" if state.pwm_us is None else state.pwm_us
    return (
        f"xyz={_num(state.x_mm)},{_num(state.y_mm)},{_num(state.z_mm)} joints={joints} "
        f"pwm={pwm} {paused} run_position={_num(state.run_position)}"
    )
