"""The static picture: SVG or PNG drawn by matplotlib, three orthographic views or one.

Strategy: a ``matplotlib.figure.Figure`` built directly (no pyplot, no GUI backend, no global
state).  Each view projects the same sampled path: one line collection per statement kind
(joint moves dashed, being approximate), each segment's line number written at its middle,
the start pose, the findings, and the workspace box where it enters the view.  A view fits
the job (its path, start pose and findings) rather than the whole workspace, so an 80 mm
square stays readable in an 800 mm box; every view is drawn at one scale with equal aspect, in
a box sized to its extent (top over front, side beside front, as a drawing office lays them
out), no side under a quarter of the longest, ticks as many as their labels have room for.  The legend panel names the kinds and lists the
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
LABEL_CELLS = 40  # a view's side holds this many line numbers: where more would overlap, one is written


def write_static(path: JobPath, output: str, fmt: str, view: str | None = None) -> None:
    """Write ``fmt`` ("svg" or "png"): the three orthographic views, or the one ``view``
    ("xy", "xz", "yz" or "3d")."""
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "armctl"}):
        figure(path, view).savefig(output, format=fmt, dpi=120, metadata=_metadata(fmt))


# The page, in inches: the views are laid out by hand at one scale (no layout engine: it cost a
# second a figure), the legend in a column of its own on the right.
FIGURE_WIDTH_IN = 14.0
LEGEND_WIDTH_IN = 6.2  # MAX_ROW_CHARS of 7-point monospace
MARGIN_LEFT_IN, MARGIN_RIGHT_IN, GAP_IN = 0.9, 0.3, 0.95  # a gap holds the next view's tick labels
MARGIN_TOP_IN, MARGIN_BOTTOM_IN = 0.75, 0.65
MIN_HEIGHT_IN, MAX_HEIGHT_IN = 4.0, 15.0
LEGEND_ROW_IN, LISTING_ROW_IN = 0.19, 0.125  # a legend entry (8 pt) and a listed line (7 pt)
MIN_VIEW_IN = 1.2  # no view's side shorter than this (a flat job's view is padded instead)
TICK_SPACING_IN = {"x": 0.9, "y": 0.45}  # room one tick label needs along each axis


def figure(path: JobPath, view: str | None = None) -> Figure:
    limits = view_box(path.view_limits())
    listing = _listing(path)
    handles = _handles(path)
    # the legend column's height: its handles, then one 7-point row per listed line
    legend_in = (len(handles) + 3) * LEGEND_ROW_IN + (listing.count("\n") + 1) * LISTING_ROW_IN
    if view == "3d":
        height_in = max(7.5, legend_in + MARGIN_TOP_IN + MARGIN_BOTTOM_IN)
        fig = Figure(figsize=(FIGURE_WIDTH_IN, height_in))
        legend_left = 1 - (LEGEND_WIDTH_IN + MARGIN_RIGHT_IN) / FIGURE_WIDTH_IN
        _draw_3d(fig.add_axes((0.02, 0.06, legend_left - 0.04, 0.86), projection="3d"), path, limits)
        legend_box = (legend_left, MARGIN_BOTTOM_IN / height_in, LEGEND_WIDTH_IN / FIGURE_WIDTH_IN,
                      1 - (MARGIN_TOP_IN + MARGIN_BOTTOM_IN) / height_in)
    else:
        fig, boxes, legend_box = _page(limits, STATIC_VIEWS if view is None else (view,), legend_in)
        for name, box in boxes.items():
            _draw_view(fig.add_axes(box), path, name, limits)
    _draw_legend(fig.add_axes(legend_box), handles, listing)
    fig.suptitle(title(path), fontsize=11)
    return fig


def view_box(limits, min_share: float = 0.25):
    """``limits`` (X, Y, Z) with each span widened, about its middle, to at least ``min_share``
    of the longest: a job flat in one axis still gets a view that holds its ticks."""
    longest = max(high - low for low, high in limits)
    out = []
    for low, high in limits:
        grow = max(0.0, longest * min_share - (high - low)) / 2
        out.append((low - grow, high + grow))
    return tuple(out)


def _page(limits, views, legend_in: float) -> tuple[Figure, dict, tuple]:
    """The figure and each view's box (figure fractions), every view at one scale (mm per
    inch) so that equal aspect fills its box: top view over front view (X shared), side view
    right of the front view (Z shared), the legend in the right-hand column."""
    span = {letter: high - low for letter, (low, high) in zip("xyz", limits)}
    columns = [views[0][0]] if len(views) == 1 else ["x", "y"]
    rows = [views[0][1]] if len(views) == 1 else ["y", "z"]
    gaps_w = MARGIN_LEFT_IN + GAP_IN * len(columns) + MARGIN_RIGHT_IN
    scale = (FIGURE_WIDTH_IN - LEGEND_WIDTH_IN - gaps_w) / sum(span[c] for c in columns)  # inches per mm
    gaps_h = MARGIN_TOP_IN + MARGIN_BOTTOM_IN + GAP_IN * (len(rows) - 1)
    scale = min(scale, (MAX_HEIGHT_IN - gaps_h) / sum(span[r] for r in rows))
    scale = max(scale, MIN_VIEW_IN / min(span.values()))
    widths = [span[c] * scale for c in columns]
    heights = [span[r] * scale for r in rows]
    height_in = max(MIN_HEIGHT_IN, gaps_h + sum(heights), MARGIN_TOP_IN + MARGIN_BOTTOM_IN + legend_in)
    width_in = gaps_w + sum(widths) + LEGEND_WIDTH_IN  # as wide as the views need: no empty band
    fig = Figure(figsize=(width_in, height_in))

    def box(column: int, row: int) -> tuple[float, float, float, float]:
        left = MARGIN_LEFT_IN + sum(widths[:column]) + GAP_IN * column
        top = height_in - MARGIN_TOP_IN - sum(heights[:row]) - GAP_IN * row
        return (left / width_in, (top - heights[row]) / height_in, widths[column] / width_in, heights[row] / height_in)

    if len(views) == 1:
        boxes = {views[0]: box(0, 0)}
    else:
        boxes = {"xy": box(0, 0), "xz": box(0, 1), "yz": box(1, 1)}
    legend_left = (width_in - LEGEND_WIDTH_IN) / width_in
    legend = (legend_left, MARGIN_BOTTOM_IN / height_in, LEGEND_WIDTH_IN / width_in - MARGIN_RIGHT_IN / width_in,
              1 - (MARGIN_TOP_IN + MARGIN_BOTTOM_IN) / height_in)
    return fig, boxes, legend


def _metadata(fmt: str) -> dict:
    # No creation date: the same job gives the same file.
    return {"Date": None} if fmt == "svg" else {}


def _project(point, axes: str):
    return tuple(point[_AXIS_INDEX[letter]] for letter in axes)


def _draw_view(ax, path: JobPath, view: str, limits) -> None:
    ax.set_gid(f"view-{view}")
    ax.set_title(VIEW_TITLES[view], fontsize=10)
    ax.set_xlabel(AXIS_TITLES[view[0]])
    ax.set_ylabel(AXIS_TITLES[view[1]])
    box = [[_project(a, view), _project(b, view)] for a, b in path.workspace.edges()]
    ax.add_collection(LineCollection(box, colors=WORKSPACE_COLOR, linewidths=0.8, gid=f"workspace-{view}"))
    numbered = 0
    view_limits = [limits[_AXIS_INDEX[letter]] for letter in view]
    label_cell = [max((high - low) / LABEL_CELLS, 1e-9) for low, high in view_limits]
    labelled: set = set()
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
            x, y = _project(segment.points[len(segment.points) // 2], view)
            cell = (round(x / label_cell[0]), round(y / label_cell[1]))
            if numbered < MAX_NUMBERED and cell not in labelled:  # one number where several would overlap
                numbered += 1
                labelled.add(cell)
                ax.annotate(str(segment.line), (x, y), xytext=(3, 3), textcoords="offset points", fontsize=7,
                            color=color)
    sx, sy = _project(path.start, view)
    ax.plot([sx], [sy], linestyle="none", marker="D", markersize=6, color=START_COLOR, gid=f"start-{view}")
    for finding in path.findings:
        x, y = _project(finding.point, view)
        ax.plot([x], [y], linestyle="none", marker="X", markersize=9, color=SEVERITY_COLORS[finding.diagnostic.severity])
    (x_low, x_high), (y_low, y_high) = view_limits
    ax.set_xlim(x_low, x_high)
    ax.set_ylim(y_low, y_high)
    ax.set_aspect("equal", adjustable="box")
    _readable_ticks(ax)
    ax.grid(True, linewidth=0.3)


def _readable_ticks(ax) -> None:
    """As many ticks as the view's sides hold labels (round steps): none overlap."""
    from matplotlib.ticker import MaxNLocator

    fig = ax.get_figure()
    left, bottom, width, height = ax.get_position().bounds
    width_in, height_in = width * fig.get_figwidth(), height * fig.get_figheight()
    for axis, length_in, spacing in ((ax.xaxis, width_in, TICK_SPACING_IN["x"]), (ax.yaxis, height_in, TICK_SPACING_IN["y"])):
        axis.set_major_locator(MaxNLocator(nbins=max(2, int(length_in / spacing)), steps=[1, 2, 2.5, 5, 10]))


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


def _draw_3d(ax, path: JobPath, limits) -> None:
    ax.set_gid("view-3d")
    ax.set_title(VIEW_TITLES["3d"], fontsize=10)
    for setter, (low, high) in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), limits):
        setter(low, high)
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


def _handles(path: JobPath) -> list:
    """The legend's entries: the kinds, start, box and findings."""
    handles = [Line2D([], [], color=KIND_COLORS[kind], linestyle="--" if kind == "joint" else "-",
                      marker="o" if kind == STILL else None, label=kind_name(kind)) for kind in path.kinds]
    handles.append(Line2D([], [], color=START_COLOR, marker="D", linestyle="none", label=start_name()))
    handles.append(Line2D([], [], color=WORKSPACE_COLOR, label=workspace_name(path.workspace)))
    for severity in ("error", "warning"):
        count = sum(1 for f in path.findings if f.diagnostic.severity == severity)
        if count:
            handles.append(Line2D([], [], color=SEVERITY_COLORS[severity], marker="X", linestyle="none",
                                  label=findings_name(severity, count)))
    return handles


def _draw_legend(ax, handles: list, listing: str) -> None:
    """The legend at the top of its column, the script line of every segment right below it."""
    from matplotlib.transforms import offset_copy

    ax.axis("off")
    legend = ax.legend(handles=handles, loc="upper left", fontsize=8, frameon=False, title="armctl plot",
                       borderaxespad=0)
    legend.set_gid("legend")
    below = offset_copy(ax.transAxes, fig=ax.get_figure(), y=-(len(handles) + 2) * LEGEND_ROW_IN * 72, units="points")
    ax.text(0.0, 1.0, listing, transform=below, va="top", ha="left", fontsize=7, family="monospace", gid="legend-lines")


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
