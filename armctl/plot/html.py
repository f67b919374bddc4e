"""The interactive picture: one self-contained HTML file drawn by plotly.

Strategy: one plotly trace per statement kind present (its segments joined into one polyline
with gaps, so a million-point job is still a handful of traces), then the start pose, the
workspace box and one trace per finding severity.  Every point carries its segment's hover
text (line, source, notes); each trace's ``meta`` names what it shows, so tests and tools can
read the figure back.  plotly.js is embedded (``include_plotlyjs=True``): the file opens
offline, with no CDN.  Imported only by ``armctl plot`` once the plot extra is known to be
installed.
"""

from __future__ import annotations

import plotly.graph_objects as go

from .path import JobPath, STILL
from .style import (
    AXIS_TITLES, KIND_COLORS, SEVERITY_COLORS, START_COLOR, VIEW_TITLES, WORKSPACE_COLOR, findings_name, kind_name,
    start_name, title, workspace_name,
)

_AXIS_INDEX = {"x": 0, "y": 1, "z": 2}
DIV_ID = "armctl-plot"  # a fixed id: the same job gives the same file
_END_MARKER_PX = 4  # a dot at each segment's ends (and at a segment that is one point)


def figure(path: JobPath, view: str = "3d") -> go.Figure:
    """The figure of ``path``: ``view`` "3d", or the orthographic "xy", "xz", "yz"."""
    axes = "xyz" if view == "3d" else view
    fig = go.Figure()
    fig.add_trace(_trace(axes, _box_polyline(path), mode="lines", name=workspace_name(path.workspace),
                         line=dict(color=WORKSPACE_COLOR, width=1), hoverinfo="skip",
                         meta={"armctl": "workspace"}))
    for kind in path.kinds:
        segments = path.of_kind(kind)
        coords, texts, sizes = [], [], []
        for segment in segments:
            if coords:
                coords.append(None)
                texts.append(None)
                sizes.append(0)
            hover = segment.describe().replace("\n", "<br>")
            last = len(segment.points) - 1
            for k, point in enumerate(segment.points):
                coords.append(point)
                texts.append(hover)
                sizes.append(_END_MARKER_PX if k in (0, last) else 0)
        line = dict(color=KIND_COLORS[kind], width=4 if view == "3d" else 2)
        if kind == "joint":
            line["dash"] = "dash"
        fig.add_trace(_trace(axes, coords, mode="markers" if kind == STILL else "lines+markers",
                             name=kind_name(kind), line=line,
                             marker=dict(color=KIND_COLORS[kind], size=8 if kind == STILL else sizes),
                             text=texts, hovertemplate=_hover(axes),
                             meta={"armctl": "kind", "kind": kind, "segments": len(segments)}))
    fig.add_trace(_trace(axes, [path.start], mode="markers", name=start_name(),
                         marker=dict(color=START_COLOR, size=8, symbol="diamond"),
                         text=[start_name()], hovertemplate=_hover(axes), meta={"armctl": "start"}))
    for severity in ("error", "warning"):
        found = [f for f in path.findings if f.diagnostic.severity == severity]
        if found:
            fig.add_trace(_trace(axes, [f.point for f in found], mode="markers",
                                 name=findings_name(severity, len(found)),
                                 marker=dict(color=SEVERITY_COLORS[severity], size=9, symbol="x"),
                                 text=[f.describe() for f in found], hovertemplate=_hover(axes),
                                 meta={"armctl": "findings", "severity": severity, "count": len(found)}))
    _layout(fig, path, view, axes)
    return fig


def write_html(path: JobPath, output: str, view: str = "3d") -> None:
    figure(path, view).write_html(output, include_plotlyjs=True, full_html=True, div_id=DIV_ID,
                                  config={"displaylogo": False, "responsive": True})


def _trace(axes: str, points, **options):
    """A Scatter3d (three axes) or Scatter (two) of ``points``; None makes a gap."""
    columns = {letter: [None if p is None else p[_AXIS_INDEX[letter]] for p in points] for letter in axes}
    if len(axes) == 3:
        return go.Scatter3d(x=columns["x"], y=columns["y"], z=columns["z"], **options)
    return go.Scatter(x=columns[axes[0]], y=columns[axes[1]], **options)


def _hover(axes: str) -> str:
    names = ("x", "y", "z") if len(axes) == 3 else ("x", "y")
    where = "  ".join(f"{letter.upper()} %{{{name}:.1f}}" for letter, name in zip(axes, names))
    return f"%{{text}}<br>{where} mm<extra></extra>"


def _box_polyline(path: JobPath) -> list:
    points = []
    for a, b in path.workspace.edges():
        points += [a, b, None]
    return points[:-1]


def _layout(fig: go.Figure, path: JobPath, view: str, axes: str) -> None:
    notes = []
    if path.approximate:
        notes.append("dashed: joint moves, drawn through the profile's kinematics (not verified against your arm)")
    if path.omitted:
        notes.append(f"{path.omitted} later segments not drawn")
    subtitle = "; ".join(notes)
    fig.update_layout(
        title=dict(text=title(path) + (f"<br><sup>{subtitle}</sup>" if subtitle else "")),
        legend=dict(itemsizing="constant"), hovermode="closest", template="plotly_white",
    )
    limits = path.view_limits()  # frame the job; the box shows where it comes near
    if view == "3d":
        spans = [high - low for low, high in limits]
        largest = max(spans)
        fig.update_layout(scene=dict(
            aspectmode="manual", aspectratio=dict(zip("xyz", (span / largest for span in spans))),
            **{f"{letter}axis": dict(title=AXIS_TITLES[letter], range=list(limits[k])) for k, letter in enumerate("xyz")},
        ))
    else:
        first, second = (_AXIS_INDEX[letter] for letter in axes)
        fig.update_xaxes(title=f"{AXIS_TITLES[axes[0]]}, {VIEW_TITLES[view]}", range=list(limits[first]))
        fig.update_yaxes(title=AXIS_TITLES[axes[1]], range=list(limits[second]), scaleanchor="x", scaleratio=1)
