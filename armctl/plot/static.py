"""The static picture: SVG or PNG drawn by matplotlib, three orthographic views or one.

Strategy: a ``matplotlib.figure.Figure`` built directly (no pyplot, no GUI backend, no global
state).  Each view projects the same sampled path: one line collection per statement kind
(joint moves dashed, being approximate), each segment's line number written at its middle,
the start pose, the findings, and the workspace box where it enters the view.  A view fits
the job (its path, start pose and findings) rather than the whole workspace, so an 80 mm
square stays readable in an 800 mm box.  The legend panel names the kinds and lists the
script line of every segment drawn.  Artists carry ``gid``s (``view-xy``, ``legend``, …)
that the SVG keeps as element ids, and SVG text stays text, so the file can be checked and
searched.  Imported only by ``armctl plot`` once the plot extra is known to be installed.
"""

from __future__ import annotations

import matplotlib
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from .path import STILL, JobPath
from .style import (
    AXIS_TITLES, KIND_COLORS, SEVERITY_COLORS, START_COLOR, STATIC_VIEWS, VIEW_TITLES, WORKSPACE_COLOR,
    findings_name, kind_name, start_name, title, workspace_name,
)

_AXIS_INDEX = {"x": 0, "y": 1, "z": 2}
MAX_LISTED = 40  # segment and finding lines listed in the legend panel; the rest are counted
MAX_ROW_CHARS = 100  # of one listed line
MAX_NUMBERED = 200  # segments whose line number is written in a view


def write_static(path: JobPath, output: str, fmt: str, view: str | None = None) -> None:
    """Write ``fmt`` ("svg" or "png"): the three orthographic views, or the one ``view``
    ("xy", "xz", "yz" or "3d")."""
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "armctl"}):
        figure(path, view).savefig(output, format=fmt, dpi=120, metadata=_metadata(fmt))


def figure(path: JobPath, view: str | None = None) -> Figure:
    views = STATIC_VIEWS if view is None else (view,)
    if len(views) == 3:
        fig = Figure(figsize=(14, 11), layout="constrained")
        grid = fig.add_gridspec(2, 2)
        cells = [grid[0, 0], grid[1, 0], grid[1, 1]]
        legend_cell = grid[0, 1]
    else:
        fig = Figure(figsize=(14, 7), layout="constrained")
        grid = fig.add_gridspec(1, 2, width_ratios=(3, 2))
        cells, legend_cell = [grid[0, 0]], grid[0, 1]
    for name, cell in zip(views, cells):
        if name == "3d":
            _draw_3d(fig.add_subplot(cell, projection="3d"), path)
        else:
            _draw_view(fig.add_subplot(cell), path, name)
    _draw_legend(fig.add_subplot(legend_cell), path)
    fig.suptitle(title(path), fontsize=11)
    return fig


def _metadata(fmt: str) -> dict:
    # No creation date: the same job gives the same file.
    return {"Date": None} if fmt == "svg" else {}


def _project(point, axes: str):
    return tuple(point[_AXIS_INDEX[letter]] for letter in axes)


def _draw_view(ax, path: JobPath, view: str) -> None:
    ax.set_gid(f"view-{view}")
    ax.set_title(VIEW_TITLES[view], fontsize=10)
    ax.set_xlabel(AXIS_TITLES[view[0]])
    ax.set_ylabel(AXIS_TITLES[view[1]])
    box = [[_project(a, view), _project(b, view)] for a, b in path.workspace.edges()]
    ax.add_collection(LineCollection(box, colors=WORKSPACE_COLOR, linewidths=0.8, gid=f"workspace-{view}"))
    numbered = 0
    for kind in path.kinds:
        segments = path.of_kind(kind)
        color = KIND_COLORS[kind]
        if kind == STILL:
            xs, ys = zip(*(_project(s.points[-1], view) for s in segments))
            ax.plot(xs, ys, linestyle="none", marker="o", markersize=5, color=color, gid=f"kind-{kind}-{view}")
        else:
            lines = [[_project(p, view) for p in s.points] for s in segments]
            ax.add_collection(LineCollection(lines, colors=color, linewidths=1.6,
                                             linestyles="--" if kind == "joint" else "-", gid=f"kind-{kind}-{view}"))
            ends = [_project(s.points[-1], view) for s in segments]
            ax.plot(*zip(*ends), linestyle="none", marker=".", markersize=4, color=color)
        for segment in segments:
            if numbered < MAX_NUMBERED:
                numbered += 1
                x, y = _project(segment.points[len(segment.points) // 2], view)
                ax.annotate(str(segment.line), (x, y), xytext=(3, 3), textcoords="offset points", fontsize=7,
                            color=color)
    sx, sy = _project(path.start, view)
    ax.plot([sx], [sy], linestyle="none", marker="D", markersize=6, color=START_COLOR, gid=f"start-{view}")
    for finding in path.findings:
        x, y = _project(finding.point, view)
        ax.plot([x], [y], linestyle="none", marker="X", markersize=9, color=SEVERITY_COLORS[finding.diagnostic.severity])
    _fit(ax, path, view)
    ax.set_aspect("equal", adjustable="box")
    ax.grid(True, linewidth=0.3)


def _fit(ax, path: JobPath, axes: str) -> list[tuple[float, float]]:
    """Set the view's limits around the job (path.view_limits); returns them."""
    around = path.view_limits()  # once: it walks every sampled point
    limits = [around[_AXIS_INDEX[letter]] for letter in axes]
    for setter, (low, high) in zip((ax.set_xlim, ax.set_ylim, getattr(ax, "set_zlim", None)), limits):
        setter(low, high)
    return limits


def _clip_edge(a, b, limits):
    """The part of an axis-parallel edge inside the box ``limits`` (x, y, z), or None."""
    low, high = list(a), list(b)
    for k, (lo, hi) in enumerate(limits):
        first, last = sorted((a[k], b[k]))
        first, last = max(first, lo), min(last, hi)
        if first > last:
            return None
        low[k], high[k] = first, last
    return tuple(low), tuple(high)


def _draw_3d(ax, path: JobPath) -> None:
    ax.set_gid("view-3d")
    ax.set_title(VIEW_TITLES["3d"], fontsize=10)
    limits = _fit(ax, path, "xyz")
    for a, b in path.workspace.edges():  # mplot3d does not clip: keep the parts inside the view
        edge = _clip_edge(a, b, limits)
        if edge is not None:
            ax.plot(*zip(*edge), color=WORKSPACE_COLOR, linewidth=0.8)
    for kind in path.kinds:
        for segment in path.of_kind(kind):
            style = dict(marker="o", linestyle="none") if kind == STILL else dict(linestyle="--" if kind == "joint" else "-")
            ax.plot(*zip(*segment.points), color=KIND_COLORS[kind], linewidth=1.6, **style)
    ax.plot(*zip(path.start), marker="D", linestyle="none", color=START_COLOR)
    for finding in path.findings:
        ax.plot(*zip(finding.point), marker="X", linestyle="none", markersize=9,
                color=SEVERITY_COLORS[finding.diagnostic.severity])
    ax.set_xlabel(AXIS_TITLES["x"])
    ax.set_ylabel(AXIS_TITLES["y"])
    ax.set_zlabel(AXIS_TITLES["z"])
    ax.set_aspect("equal", adjustable="box")


def _draw_legend(ax, path: JobPath) -> None:
    """The kinds, start, box and findings as a legend, then the script line of every segment."""
    ax.axis("off")
    handles = [Line2D([], [], color=KIND_COLORS[kind], linestyle="--" if kind == "joint" else "-",
                      marker="o" if kind == STILL else None, label=kind_name(kind)) for kind in path.kinds]
    handles.append(Line2D([], [], color=START_COLOR, marker="D", linestyle="none", label=start_name()))
    handles.append(Line2D([], [], color=WORKSPACE_COLOR, label=workspace_name(path.workspace)))
    for severity in ("error", "warning"):
        count = sum(1 for f in path.findings if f.diagnostic.severity == severity)
        if count:
            handles.append(Line2D([], [], color=SEVERITY_COLORS[severity], marker="X", linestyle="none",
                                  label=findings_name(severity, count)))
    legend = ax.legend(handles=handles, loc="upper left", fontsize=8, frameon=False, title="armctl plot")
    legend.set_gid("legend")
    ax.text(0.0, 0.62, _listing(path), transform=ax.transAxes, va="top", ha="left", fontsize=7, family="monospace",
            gid="legend-lines")


def _listing(path: JobPath) -> str:
    """One line per segment (its line number and source), then the findings; capped."""
    rows, seen = [], set()
    for segment in path.segments:
        if segment.label not in seen:
            seen.add(segment.label)
            rows.append(f"{segment.kind:<6} {segment.label}: {segment.text}")
    rows += [f"! {finding.describe()}" for finding in path.findings]
    if path.omitted:
        rows.append(f"({path.omitted} later segments not drawn)")
    shown = [row if len(row) <= MAX_ROW_CHARS else row[: MAX_ROW_CHARS - 1] + "…" for row in rows[:MAX_LISTED]]
    if len(rows) > MAX_LISTED:
        shown.append(f"… and {len(rows) - MAX_LISTED} more")
    return "\n".join(shown)
