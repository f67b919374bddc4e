"""``armctl plot`` as a user sees it: exit codes, diagnostics, the missing extra, and the files.

In-process through click's CliRunner on armctl's own group (so the registration is tested)
and through the installed command in a fresh process.  The HTML is read back structurally
(the figure JSON plotly writes), the SVG as XML (artists carry ids), the PNG as pixels.
Tests that need plotly or matplotlib skip without the plot extra; the ones about usage, the
diagnostics and the missing extra run everywhere.  Every test runs in an empty working
directory, so no armctl.toml from the checkout changes the profile.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main

ROOT = Path(__file__).resolve().parents[1]
SQUARE = ROOT / "scripts" / "draw_square_circle.txt"
FIRST = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000"
BAD = f"{FIRST}\n#<unused> = 5\nG1 X500\nG1 Q5\nG4 P100\nG6 J1=30 J2=10 J3=0 J4=0 J5=90 J6=0 F30\n"
INSTALL = "pip install -e '.[plot]'"


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def plot(*args):
    return CliRunner().invoke(main, ["plot", *map(str, args)], catch_exceptions=False)


def armctl(*args, env=None, cwd=None):
    """The installed command in a fresh process."""
    return subprocess.run([sys.executable, "-m", "armctl", *map(str, args)], capture_output=True, text=True,
                          timeout=120, env=env, cwd=cwd)


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def figure_of(html: str) -> tuple[list, dict]:
    """The traces and layout plotly wrote into the HTML's Plotly.newPlot call."""
    start = html.index("Plotly.newPlot(") + len("Plotly.newPlot(")
    decoder = json.JSONDecoder()
    position = start
    values = []
    for _ in range(3):  # the div id, the traces, the layout
        while html[position] in " \n\t,":
            position += 1
        value, position = decoder.raw_decode(html, position)
        values.append(value)
    return values[1], values[2]


def runs(values) -> int:
    """Polylines in a trace's coordinates: runs separated by None."""
    count, inside = 0, False
    for value in values:
        if value is None:
            inside = False
        elif not inside:
            count, inside = count + 1, True
    return count


def traces_of(traces, what):
    return [t for t in traces if (t.get("meta") or {}).get("armctl") == what]


# --- registration and the missing extra ----------------------------------------------------------------


def test_help_lists_plot_and_imports_no_plotting_library():
    done = subprocess.run(
        [sys.executable, "-c",
         "import sys\nfrom armctl.ui.cli import main\n"
         "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
         "print('LOADED', sorted(m for m in ('plotly', 'matplotlib') if m in sys.modules))"],
        capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert re.search(r"^\s+plot\s", done.stdout, re.M)
    assert "LOADED []" in done.stdout


@pytest.mark.parametrize("suffix, library", [(".html", "plotly"), (".svg", "matplotlib"), (".png", "matplotlib")])
def test_without_the_extra_plot_says_what_to_install(tmp_path, monkeypatch, suffix, library):
    monkeypatch.setitem(sys.modules, library, None)  # import fails as if not installed
    result = plot(SQUARE, "-o", tmp_path / f"job{suffix}")
    assert result.exit_code == 2
    assert INSTALL in result.output and library in result.output
    assert not (tmp_path / f"job{suffix}").exists()


def test_without_the_extra_in_a_fresh_process(tmp_path):
    blocker = tmp_path / "blocked"
    blocker.mkdir()
    for name in ("plotly", "matplotlib"):
        write(blocker / f"{name}.py", f"raise ModuleNotFoundError('No module named {name}', name='{name}')\n")
    env = {**__import__("os").environ, "PYTHONPATH": str(blocker)}
    done = armctl("plot", SQUARE, "-o", tmp_path / "job.html", env=env)
    assert done.returncode == 2, done.stderr
    assert INSTALL in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "job.html").exists()


def test_the_extra_and_the_package_are_declared():
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    extra = project["project"]["optional-dependencies"]["plot"]
    assert {requirement.split(">")[0] for requirement in extra} == {"plotly", "matplotlib"}
    assert "armctl.plot" in project["tool"]["setuptools"]["packages"]  # the wheel ships the command


# --- usage errors and bad scripts (no extra needed: they stop before drawing) ----------------------------


@pytest.mark.parametrize("args, message", [
    (["missing.txt", "-o", "job.html"], "cannot read missing.txt"),
    (["-", "-o", "job.html"], "plot needs a file"),
    ([SQUARE, "-o", "job.pdf"], "end it with .html, .svg or .png"),
    ([SQUARE, "-o", "job.html", "--view", "top"], "Invalid value for '--view'"),
    ([SQUARE, "-o", "job.html", "--from-line", "0"], "Invalid value for '--from-line'"),
])
def test_usage_errors_exit_2(args, message):
    result = plot(*args)
    assert result.exit_code == 2
    assert message in result.output
    assert "Traceback" not in result.output


def test_a_bad_profile_exits_2(tmp_path, monkeypatch):
    pytest.importorskip("plotly")
    profile = write(tmp_path / "arm.toml", "[speed]\nmax_linear_mm_min = -1\n")
    result = plot(SQUARE, "-o", "job.html", "--profile", profile)
    assert result.exit_code == 2 and "arm.toml" in result.output
    assert not Path("job.html").exists()


def users_profile(tmp_path) -> Path:
    """The packaged numbers given as the user's own profile: their workspace findings are errors
    (on the built-in, illustrative profile they are warnings: tests/test_lint_provenance.py)."""
    from importlib import resources

    path = tmp_path / "my_arm.toml"
    path.write_bytes(resources.files("armctl.data").joinpath("default_profile.toml").read_bytes())
    return path


def test_a_script_with_errors_is_not_drawn_and_reported_as_lint_reports_it(tmp_path):
    pytest.importorskip("plotly")
    script = write(tmp_path / "job.txt", BAD)
    profile = users_profile(tmp_path)
    result = plot(script, "-o", "job.html", "--profile", profile)
    assert result.exit_code == 1
    assert "2 errors: nothing was drawn" in result.output
    assert not Path("job.html").exists()
    lint = CliRunner().invoke(main, ["lint", str(script), "--profile", str(profile)])
    findings = lint.stdout.rsplit("Found ", 1)[0]  # lint's text without its summary line
    assert findings.count(f"{script}:") == 3  # L401, L103, E002
    assert result.stderr.startswith(findings)
    assert f"{script}:4:4: E002 unknown word 'Q' in G1" in result.stderr


def test_a_resume_line_inside_an_arc_is_an_error(tmp_path):
    pytest.importorskip("plotly")
    result = plot(SQUARE, "-o", "job.html", "--from-line", "25")
    assert result.exit_code == 1 and "E010" in result.output
    assert not Path("job.html").exists()


def test_an_unwritable_output_exits_2(tmp_path):
    pytest.importorskip("plotly")
    result = plot(SQUARE, "-o", tmp_path / "no" / "such" / "dir" / "job.html")
    assert result.exit_code == 2 and "cannot write" in result.output


# --- the HTML ----------------------------------------------------------------------------------------------


def test_html_of_the_example_job(tmp_path):
    pytest.importorskip("plotly")
    result = plot(SQUARE, "-o", tmp_path / "job.html")
    assert result.exit_code == 0, result.output
    assert "14 segments (linear 11, arc 2, joint 1)" in result.output
    assert "approximate" in result.output
    html = (tmp_path / "job.html").read_text(encoding="utf-8")
    # self-contained: plotly.js is inside, nothing is loaded from elsewhere
    assert not re.search(r"<script[^>]*\bsrc=", html)
    assert "plotly.js v" in html
    traces, layout = figure_of(html)
    kinds = traces_of(traces, "kind")
    assert [t["meta"]["kind"] for t in kinds] == ["linear", "arc", "joint"]  # one trace per kind present
    assert {t["meta"]["kind"]: runs(t["x"]) for t in kinds} == {"linear": 11, "arc": 2, "joint": 1}
    assert all(t["type"] == "scatter3d" for t in kinds)
    linear_text = set(kinds[0]["text"]) - {None}
    assert any(text.startswith("line 15: G1 X290 F1200 ; first side") for text in linear_text)
    arc_text = set(kinds[1]["text"]) - {None}
    assert any(text.startswith("lines 24-25: G300 X250 Y30 Z20 R30 F900") for text in arc_text)
    joint = kinds[2]
    assert joint["line"]["dash"] == "dash" and "not verified against your arm" in joint["name"]
    assert len(traces_of(traces, "start")) == 1 and len(traces_of(traces, "workspace")) == 1
    assert traces_of(traces, "findings") == []
    assert "14 segments" in layout["title"]["text"]


def test_html_with_force_draws_the_findings(tmp_path):
    pytest.importorskip("plotly")
    script = write(tmp_path / "job.txt", BAD)
    result = plot(script, "-o", "job.html", "--force", "--profile", users_profile(tmp_path))
    assert result.exit_code == 1  # drawn, but the script still has errors
    traces, _ = figure_of(Path("job.html").read_text(encoding="utf-8"))
    found = {t["meta"]["severity"]: t for t in traces_of(traces, "findings")}
    assert found["error"]["meta"]["count"] == 2 and found["warning"]["meta"]["count"] == 1
    assert any("line 3:4 L103 error" in text for text in found["error"]["text"])
    assert (found["error"]["x"], found["error"]["y"]) == ([500, 500], [0, 0])  # L103 at its move's end, E002 where the arm is
    assert [t["meta"]["kind"] for t in traces_of(traces, "kind")] == ["linear", "joint", "still"]


@pytest.mark.parametrize("view, axes", [("xy", ("x", "y")), ("yz", ("y", "z"))])
def test_html_orthographic_view(tmp_path, view, axes):
    pytest.importorskip("plotly")
    assert plot(SQUARE, "-o", "job.html", "--view", view).exit_code == 0
    traces, layout = figure_of(Path("job.html").read_text(encoding="utf-8"))
    linear = traces_of(traces, "kind")[0]
    assert linear["type"] == "scatter" and "z" not in linear
    assert layout["yaxis"]["scaleanchor"] == "x"


def test_default_output_is_the_jobs_name_here(tmp_path):
    pytest.importorskip("plotly")
    assert plot(SQUARE).exit_code == 0
    assert Path("draw_square_circle.html").is_file()


def test_the_installed_command_writes_html(tmp_path):
    pytest.importorskip("plotly")
    done = armctl("plot", SQUARE, "-o", "job.html", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "wrote job.html: 14 segments" in done.stdout
    traces, _ = figure_of((tmp_path / "job.html").read_text(encoding="utf-8"))
    assert len(traces_of(traces, "kind")) == 3


# --- the SVG and PNG -----------------------------------------------------------------------------------------


def _ids(svg: Path) -> set[str]:
    return {element.get("id") for element in ET.parse(svg).iter() if element.get("id")}


def test_svg_holds_three_views_and_a_legend(tmp_path):
    pytest.importorskip("matplotlib")
    result = plot(SQUARE, "-o", "job.svg")
    assert result.exit_code == 0, result.output
    ids = _ids(Path("job.svg"))
    assert {"view-xy", "view-xz", "view-yz", "legend", "legend-lines"} <= ids
    for view in ("xy", "xz", "yz"):  # one drawing per statement kind in each view
        assert {i for i in ids if i.startswith("kind-") and i.endswith(f"-{view}")} == {
            f"kind-linear-{view}", f"kind-arc-{view}", f"kind-joint-{view}"}
    text = Path("job.svg").read_text(encoding="utf-8")
    assert "line 15: G1 X290 F1200 ; first side" in text  # the script line of every segment
    assert "lines 24-25: G300 X250 Y30 Z20 R30 F900" in text
    assert "not verified against your arm" in text
    assert "Ignoring fixed" not in result.output  # no matplotlib warnings for the user


def test_svg_one_view_and_findings(tmp_path):
    pytest.importorskip("matplotlib")
    script = write(tmp_path / "job.txt", BAD)
    result = plot(script, "-o", "job.svg", "--view", "xz", "--force", "--profile", users_profile(tmp_path))
    assert result.exit_code == 1
    ids = _ids(Path("job.svg"))
    assert "view-xz" in ids and not {"view-xy", "view-yz"} & ids
    text = Path("job.svg").read_text(encoding="utf-8")
    assert "lint errors (2)" in text and "lint warning (1)" in text
    assert "line 3:4 L103 error" in text


def test_png_shows_the_kinds_in_their_colours(tmp_path):
    pytest.importorskip("matplotlib")
    from matplotlib.image import imread

    from armctl.plot.style import KIND_COLORS

    assert plot(SQUARE, "-o", "job.png").exit_code == 0
    assert Path("job.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    pixels = imread("job.png")[:, :, :3]
    for kind in ("linear", "arc", "joint"):
        assert _pixels_of(pixels, KIND_COLORS[kind]) > 50, kind
    assert _pixels_of(pixels, KIND_COLORS["accel"]) == 0  # no accelerated moves in this job


def _pixels_of(pixels, color: str, tolerance: float = 0.04) -> int:
    import numpy as np

    rgb = np.array([int(color[k:k + 2], 16) / 255 for k in (1, 3, 5)])
    return int((np.abs(pixels - rgb).max(axis=2) <= tolerance).sum())


def test_3d_png(tmp_path):
    pytest.importorskip("matplotlib")
    assert plot(SQUARE, "-o", "job.png", "--view", "3d").exit_code == 0
    assert Path("job.png").stat().st_size > 10_000


# --- a real browser -------------------------------------------------------------------------------------------


BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def test_a_headless_browser_draws_the_html_in_3d(tmp_path):
    """One browser start (several seconds: plotly.js is 4 MB of script), the 3D view through
    WebGL (SwiftShader where there is no GPU)."""
    pytest.importorskip("plotly")
    np = pytest.importorskip("numpy")
    from matplotlib.image import imread

    from armctl.plot.style import KIND_COLORS

    browser = next((found for name in BROWSERS if (found := shutil.which(name))), None)
    if browser is None:
        pytest.skip(f"no headless browser on this machine (looked for {', '.join(BROWSERS)})")
    assert plot(SQUARE, "-o", "job.html").exit_code == 0
    shot = tmp_path / "shot.png"
    done = subprocess.run(
        [browser, "--headless", "--no-sandbox", "--disable-gpu", "--use-gl=swiftshader", "--enable-unsafe-swiftshader",
         "--window-size=1200,800", "--virtual-time-budget=5000", f"--screenshot={shot}",
         (tmp_path / "job.html").as_uri()],
        capture_output=True, text=True, timeout=120)
    assert shot.is_file(), done.stderr[-2000:]
    pixels = imread(shot)[:, :, :3]
    assert np.asarray(pixels).std() > 0  # not a blank page
    for kind in ("linear", "arc"):  # the square and the circle, drawn by plotly.js offline
        assert _pixels_of(pixels, KIND_COLORS[kind], tolerance=0.08) > 30, kind
