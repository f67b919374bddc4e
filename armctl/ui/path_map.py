"""The run panel's map: a top view (X/Y) of the job as braille characters, coloured by progress.

Strategy: the path is sampled once, before the stream starts, by ``armctl plot``'s own pure
sampler (``armctl.plot.path.build_path``: the motion model's geometry, never a second one),
bounded to the first ``MAP_MAX_FRAMES`` frames so a huge job costs a bounded time and memory.
``rasterise`` then draws every polyline into a fixed grid of braille dots (2×4 dots a
character, so a dot is about square on a terminal and X and Y share one scale) and keeps, for
each dot, the frame ordinal of the last move that passes through it: the dot has nothing left
to do once that frame is done.  That grid is computed once; a refresh (~10×/s) only compares
those ordinals with two counters of the ``RunView`` — frames written, frames known done — so
it costs one pass over a few hundred characters, and nothing when the counters did not move.

A character is *done* when every move through it is known done, *queued* when every move
through it was written (it waits in the connector or is under way), and *not sent* otherwise.
The shape says it too, so a terminal without colours still shows progress: dots of moves
already written are drawn solid, dots of moves not yet written dotted (every other dot along
the line).  The arm's reported position is one marker character on top.

Pure: points and counters in, characters and state names out; the rich styling is
run_panel.py's.  Points are in the robot frame, mm (``build_path``'s frame); the caller gives
the worktable origin that turns the arm's reported (worktable) X/Y into that frame — the
origin the job starts with: after a G54 inside the job the marker is off by the shift (the
view holds no later origin report).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Iterable, Iterator, Optional, Sequence

# States of a character, in the order of progress; EMPTY has no path in it.
EMPTY, TODO, QUEUED, DONE, ARM = "empty", "todo", "queued", "done", "arm"
ARM_GLYPH = "◉"

MAP_WIDTH_CHARS, MAP_HEIGHT_ROWS = 40, 10  # the grid: 80 × 40 dots
# Frames sampled for the map (a longer job's map shows its first ones): the sampling runs before
# the first frame is sent, so it is bounded; measured on a loaded 2-core machine, 5000 frames
# took 0.3 s as G1 lines and 1.6 s as wide arcs (plot samples an arc every 5 degrees).
MAP_MAX_FRAMES = 5_000
MAP_MARGIN_MM = 2.0  # around the job, so its outline does not run along the grid's edge
COORDINATE_LIMIT_MM = 1e9  # points beyond are clamped here (no arm reaches a kilometre)
MIN_EXTENT_MM = 1.0  # a job that moves less than this in X and in Y has no top view

# Braille: dot (column c of 2, row r of 4) of a character is this bit above U+2800.
_BRAILLE_BASE = 0x2800
_BRAILLE_BITS = ((0x01, 0x08), (0x02, 0x10), (0x04, 0x20), (0x40, 0x80))

Point2 = tuple[float, float]


@dataclass
class _Cell:
    """One character of the grid: its dots (bit, frame ordinal, drawn when not yet sent)."""

    dots: dict = field(default_factory=dict)  # bit -> [ordinal, dotted_visible]
    last_ordinal: int = -1  # the latest frame through any of its dots


@dataclass
class PathGrid:
    """A job's path rasterised once; ``rows`` draws it for the current progress."""

    width_chars: int
    height_rows: int
    x_mm: tuple[float, float]  # the X and Y the grid spans (left…right, bottom…top)
    y_mm: tuple[float, float]
    mm_per_dot: float
    frames: int  # frames sampled (the map's ordinals are 0 … frames-1)
    cells: dict = field(default_factory=dict)  # (column, row) -> _Cell
    origin_mm: tuple[float, float] = (0.0, 0.0)  # worktable origin X/Y: reported + origin = robot frame
    _cache: tuple = field(default=(None, None), repr=False, compare=False)  # the last rows drawn, by their key

    def cell_of(self, x_mm: float, y_mm: float) -> Optional[tuple[int, int]]:
        """The character a robot-frame X/Y falls in (clamped to the grid's edge), None if not finite."""
        dot = self._dot_of(x_mm, y_mm)
        return None if dot is None else (dot[0] // 2, dot[1] // 4)

    def _dot_of(self, x_mm: float, y_mm: float) -> Optional[tuple[int, int]]:
        if not (math.isfinite(x_mm) and math.isfinite(y_mm)):
            return None
        columns, rows = 2 * self.width_chars, 4 * self.height_rows
        column = _index(_clamp(x_mm) - self.x_mm[0], self.mm_per_dot, columns)
        row_from_bottom = _index(_clamp(y_mm) - self.y_mm[0], self.mm_per_dot, rows)
        return column, rows - 1 - row_from_bottom  # row 0 is the top: +Y up

    def rows(self, frames_sent: int, frames_done: int, arm_mm: Optional[Sequence[float]] = None) -> list[list[tuple[str, str]]]:
        """The grid as rows of (character, state) for ``frames_sent`` written and ``frames_done``
        known done; ``arm_mm`` the arm's reported (worktable) X, Y[, Z], or None."""
        arm = None
        if arm_mm is not None and len(arm_mm) >= 2:
            arm = self.cell_of(arm_mm[0] + self.origin_mm[0], arm_mm[1] + self.origin_mm[1])
        key = (frames_sent, frames_done, arm)
        if self._cache[0] == key:
            return self._cache[1]
        drawn = []
        for row in range(self.height_rows):
            line = []
            for column in range(self.width_chars):
                if (column, row) == arm:
                    line.append((ARM_GLYPH, ARM))
                    continue
                cell = self.cells.get((column, row))
                if cell is None:
                    line.append((" ", EMPTY))
                    continue
                bits = 0
                for bit, (ordinal, dotted_visible) in cell.dots.items():
                    if ordinal < frames_sent or dotted_visible:
                        bits |= bit
                state = DONE if cell.last_ordinal < frames_done else QUEUED if cell.last_ordinal < frames_sent else TODO
                line.append((chr(_BRAILLE_BASE + bits) if bits else " ", state if bits else EMPTY))
            drawn.append(line)
        self._cache = (key, drawn)
        return drawn

    def text_rows(self, frames_sent: int, frames_done: int, arm_mm: Optional[Sequence[float]] = None) -> list[str]:
        """``rows`` as plain strings (what a terminal without colours shows)."""
        return ["".join(char for char, _ in line) for line in self.rows(frames_sent, frames_done, arm_mm)]


def rasterise(polylines: Iterable[tuple[int, Sequence[Point2]]], *, frames: int,
              width_chars: int = MAP_WIDTH_CHARS, height_rows: int = MAP_HEIGHT_ROWS,
              origin_mm: tuple[float, float] = (0.0, 0.0), margin_mm: float = 0.0) -> Optional[PathGrid]:
    """Draw ``polylines`` — (frame ordinal, robot-frame X/Y points) in job order — into a grid
    of ``width_chars`` × ``height_rows`` characters, framed on the points with ``margin_mm``
    around them; None when they span less than MIN_EXTENT_MM in both X and Y (nothing to see
    from above).  Non-finite points are skipped; the grid's size never depends on the input."""
    lines = [(ordinal, [(_clamp(x), _clamp(y)) for x, y in points if math.isfinite(x) and math.isfinite(y)])
             for ordinal, points in polylines]
    lines = [(ordinal, points) for ordinal, points in lines if points]
    if not lines:
        return None
    xs = [p[0] for _, points in lines for p in points]
    ys = [p[1] for _, points in lines for p in points]
    low_x, high_x, low_y, high_y = min(xs), max(xs), min(ys), max(ys)
    if high_x - low_x < MIN_EXTENT_MM and high_y - low_y < MIN_EXTENT_MM:
        return None
    columns, rows = 2 * width_chars, 4 * height_rows
    span_x, span_y = high_x - low_x + 2 * margin_mm, high_y - low_y + 2 * margin_mm
    mm_per_dot = max(span_x / columns, span_y / rows)
    # centre the job: the axis with room to spare gets it on both sides
    mid_x, mid_y = (low_x + high_x) / 2, (low_y + high_y) / 2
    half_x, half_y = columns * mm_per_dot / 2, rows * mm_per_dot / 2
    grid = PathGrid(width_chars, height_rows, (mid_x - half_x, mid_x + half_x), (mid_y - half_y, mid_y + half_y),
                    mm_per_dot, frames, origin_mm=origin_mm)
    for ordinal, points in lines:
        step = 0
        for column, row in _walk([grid._dot_of(x, y) for x, y in points]):
            cell = grid.cells.setdefault((column // 2, row // 4), _Cell())
            bit = _BRAILLE_BITS[row % 4][column % 2]
            dotted_visible = step % 2 == 0
            previous = cell.dots.get(bit)
            if previous is not None and previous[0] == ordinal:
                dotted_visible = dotted_visible or previous[1]
            cell.dots[bit] = (ordinal, dotted_visible)  # ordinals come in job order: the last one wins
            cell.last_ordinal = max(cell.last_ordinal, ordinal)
            step += 1
    return grid


def _walk(dots: Sequence[tuple[int, int]]) -> Iterator[tuple[int, int]]:
    """Every dot on the straight pieces between consecutive dots (a DDA in dot space: bounded
    by the grid, whatever the millimetres were)."""
    previous = None
    for dot in dots:
        if previous is None:
            yield dot
        else:
            (x0, y0), (x1, y1) = previous, dot
            steps = max(abs(x1 - x0), abs(y1 - y0))
            for k in range(1, steps + 1):
                yield (x0 + round((x1 - x0) * k / steps), y0 + round((y1 - y0) * k / steps))
        previous = dot


def _clamp(v: float) -> float:
    return max(-COORDINATE_LIMIT_MM, min(COORDINATE_LIMIT_MM, v))


def _index(offset_mm: float, mm_per_dot: float, count: int) -> int:
    return max(0, min(count - 1, int(math.floor(offset_mm / mm_per_dot))))


def job_grid(statements: Iterable, model, start, *, max_frames: int = MAP_MAX_FRAMES,
             width_chars: int = MAP_WIDTH_CHARS, height_rows: int = MAP_HEIGHT_ROWS) -> Optional[PathGrid]:
    """The map of a compiled job (armctl.script Statements, the stream's order) planned from
    ``start`` (the streamer's start pose): ``armctl plot``'s sampling of its first
    ``max_frames`` frames, rasterised.  None for a job with nothing to see from above."""
    from ..plot.path import STILL, build_path
    from ..core.protocol import ArcStart

    # build_path makes one PathSegment for every statement but a G300 (drawn with its G301):
    # so segment k belongs to the k-th such frame, whose ordinal is recorded here.
    ordinals: list[int] = []
    sampled = 0

    def counted():
        nonlocal sampled
        for ordinal, statement in enumerate(statements):
            if ordinal >= max_frames:
                return
            sampled = ordinal + 1
            if type(statement.command) is not ArcStart:
                ordinals.append(ordinal)
            yield statement

    path = build_path(counted(), model, start=start, max_segments=max_frames)
    polylines = [(ordinals[segment.index], [(x, y) for x, y, _ in segment.points])
                 for segment in path.segments if segment.kind != STILL]  # a still frame moves nothing
    origin = tuple(start.origin_mm[:2])
    return rasterise(polylines, frames=sampled, width_chars=width_chars, height_rows=height_rows, origin_mm=origin,
                     margin_mm=MAP_MARGIN_MM)
