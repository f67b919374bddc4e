"""Issue 26 item 7: the static views sized to the path — every view at one scale with equal
aspect filling its box, no view thinner than a quarter of the longest side, tick labels that do
not overlap — for every example job and a lopsided one, in-process and through the installed
command.  The speed (under 1.5 s a job) is benchmarks/plot_speed.py's, not a timed test."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("matplotlib", reason="needs the plot extra: pip install -e '.[plot]'")

from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402

from armctl.lint.engine import lint_lines  # noqa: E402
from armctl.core.motion import MotionModel  # noqa: E402
from armctl.plot.path import build_path  # noqa: E402
from armctl.plot.static import figure  # noqa: E402
from armctl.host.profile import default_profile  # noqa: E402
from armctl.script import compile_file, compile_text  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
JOBS = sorted((ROOT / "scripts").glob("*.txt"))
LOPSIDED = "G1 X200 Y0 Z200 A180 B0 C0 S1500 F3000\nG1 X400 Y2\nG1 X-100 Y5\n"
ARMCTL = Path(sys.executable).with_name("armctl")


def _path(statements, name="job"):
    return build_path(statements, MotionModel(default_profile()), name)


def _views(fig):
    return {ax.get_gid(): ax for ax in fig.axes if (ax.get_gid() or "").startswith("view-")}


def _check_views(fig) -> None:
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    views = _views(fig)
    assert set(views) == {"view-xy", "view-xz", "view-yz"}
    scales = []
    for name, ax in views.items():
        assert ax.get_aspect() == 1.0, name
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        box = ax.get_position()
        width_in, height_in = box.width * fig.get_figwidth(), box.height * fig.get_figheight()
        # equal aspect fills the box sized to the view: no empty band inside it
        assert (x1 - x0) / (y1 - y0) == pytest.approx(width_in / height_in, rel=0.02), name
        assert min(x1 - x0, y1 - y0) >= 0.24 * max(x1 - x0, y1 - y0), name
        scales.append(width_in / (x1 - x0))
        for axis, (low, high), along in ((ax.xaxis, (x0, x1), 0), (ax.yaxis, (y0, y1), 1)):
            shown = [label for tick, label in zip(axis.get_majorticklocs(), axis.get_ticklabels())
                     if low <= tick <= high and label.get_text()]
            assert len(shown) >= 2, name
            boxes = sorted((label.get_window_extent(renderer) for label in shown), key=lambda b: (b.x0, b.y0)[along])
            for before, after in zip(boxes, boxes[1:]):
                assert (after.x0 >= before.x1) if along == 0 else (after.y0 >= before.y1), (name, axis.axis_name)
    assert max(scales) == pytest.approx(min(scales), rel=0.01)  # one scale for the three views


@pytest.mark.parametrize("job", JOBS, ids=[job.name for job in JOBS])
def test_example_jobs_views_fit_their_path(job):
    _check_views(figure(_path(compile_file(job), job.name)))


def test_a_lopsided_path_gets_readable_views():
    fig = figure(_path(compile_text(LOPSIDED, "lop.txt"), "lop.txt"))
    _check_views(fig)
    top = _views(fig)["view-xy"]
    (x0, x1), (y0, y1) = top.get_xlim(), top.get_ylim()
    assert (y1 - y0) == pytest.approx(0.25 * (x1 - x0), rel=0.01)  # widened to a quarter, not a sliver


@pytest.mark.timeout(120)
def test_the_installed_command_draws_the_lopsided_job(tmp_path):
    script = tmp_path / "lop.txt"
    script.write_text(LOPSIDED)
    done = subprocess.run([str(ARMCTL), "plot", str(script), "-o", str(tmp_path / "lop.svg"), "--force"],
                          capture_output=True, text=True, timeout=110)
    assert done.returncode == 0, done.stderr
    assert 'id="view-xy"' in (tmp_path / "lop.svg").read_text()
