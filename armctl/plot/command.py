"""``armctl plot``: the click command — options, checks, exit codes; drawing is elsewhere.

Strategy: the order a user needs.  Usage problems first (an output format we cannot write,
a script that cannot be read, a missing plot extra, a bad profile: exit 2, nothing linted),
then the same checks as ``armctl lint`` (armctl/core/checked.py's ``check``, lint's engine) with the
same located diagnostics on stderr — a script with errors is not drawn (exit 1) unless
``--force``, which draws it with its findings and still exits 1.  Then the job is compiled
and sampled by the pure armctl/plot/path.py and handed to a renderer: plotly for .html
(html.py), matplotlib for .svg/.png (static.py).  Only click is imported at module level,
and plotly/matplotlib only inside the command, so ``armctl --help`` stays fast.

Registered by the CLI with ``main.add_command(plot)``.
Exit codes: 0 drawn, 1 the script has errors (drawn only with --force), 2 usage, an
unreadable script, a missing plot extra, a bad profile or an unwritable output.
"""

from __future__ import annotations

import os
import sys

import click

from ..ui.cli_types import NamedFile, number
from ..errors import EXIT_OK, EXIT_PROBLEMS, EXIT_USAGE
from ..core.limits import LINE_RANGE

FORMATS = {".html": "html", ".htm": "html", ".svg": "svg", ".png": "png"}
LIBRARY_OF = {"html": "plotly", "svg": "matplotlib", "png": "matplotlib"}
INSTALL_HINT = "pip install -e '.[plot]'"


def _fail(message: str, code: int = EXIT_USAGE):
    click.echo(f"armctl plot: {message}", err=True)
    sys.exit(code)


@click.command(name="plot")
@click.argument("script", metavar="JOB")
@click.option("-o", "--output", type=NamedFile(), metavar="FILE",
              help="FILE.html: interactive 3D, self-contained, works offline (plotly). FILE.svg or FILE.png: "
                   "the three orthographic views (matplotlib).  [default: JOB's name with .html, here]")
@click.option("--view", type=click.Choice(["3d", "xy", "xz", "yz"]), default=None,
              help="One view only: 3d, or the orthographic top (xy), front (xz) or side (yz) view.  "
                   "[default: 3d for HTML, xy+xz+yz for SVG/PNG]")
@click.option("--from-line", type=number(*LINE_RANGE, whole=True), default=1, show_default=True, metavar="N",
              help="Draw the job as `run --from-line N` would send it (from the fixed pose 0).")
@click.option("--profile", "profile_path", metavar="FILE",
              help="Arm profile (TOML). Default: armctl.toml's [profile] (or its path), else the packaged default.")
@click.option("--force", is_flag=True, help="Draw a script with errors too, its findings marked (exit status stays 1).")
def plot(script, output, view, from_line, profile_path, force):
    """Draw the path a job takes before it runs: lines, arcs and joint moves, coloured by kind.

    Sampled from the motion model that estimate, run and the simulator use, from the
    profile's fixed pose 0, with the workspace box and every lint finding marked. Joint moves
    are drawn through the profile's kinematics: approximate, not verified against your arm.
    Needs the plot extra (pip install -e '.[plot]'). Exit status: 0 drawn, 1 the script has
    errors, 2 usage error, unreadable input or missing extra.
    """
    output = output or os.path.splitext(os.path.basename(script))[0] + ".html"
    fmt = FORMATS.get(os.path.splitext(output)[1].lower())
    if fmt is None:
        _fail(f"cannot tell what to write from the name {output!r}: end it with .html, .svg or .png")
    snapshot = _read(script)
    _require_extra(fmt)
    profile = _profile(profile_path)
    diagnostics = _check(snapshot, profile, from_line, force)
    path = _build(snapshot, profile, from_line, diagnostics)
    _render(path, output, fmt, view)
    _summary(path, output)
    sys.exit(EXIT_PROBLEMS if any(d.is_error for d in diagnostics) else EXIT_OK)


def _read(script: str):
    """The script read once (``ScriptSnapshot``): the check and the drawing see the same bytes."""
    from ..host.inputs import InputTooLarge
    from ..script import read_script

    if script == "-":
        _fail("plot needs a file (it reads the script more than once); save it first")
    try:
        return read_script(script)
    except InputTooLarge as error:
        _fail(str(error))
    except OSError as error:
        _fail(f"cannot read {script}: {error.strerror or error}")


def _require_extra(fmt: str) -> None:
    """The library this format needs, or exit 2 saying exactly what to install."""
    library = LIBRARY_OF[fmt]
    try:
        __import__(library)
    except ImportError:
        _fail(f"writing .{fmt} needs {library}, from armctl's plot extra: {INSTALL_HINT}"
              " (in armctl's checkout; installs plotly and matplotlib)")


def _profile(profile_path):
    from ..errors import ConfigError, ProfileError
    from ..host.calibration import arm_profile

    try:
        return arm_profile(profile_path)  # the configured port's arm
    except (ProfileError, ConfigError) as error:
        _fail(str(error))
    except OSError as error:
        _fail(f"cannot read {error.filename or profile_path}: {error.strerror or error}")


def _check(snapshot, profile, from_line: int, force: bool) -> list:
    """Lint's findings (and a bad --from-line) on stderr; exit 1 on errors unless ``force``."""
    from ..core.checked import check
    from ..lint.formatters import TextFormatter

    report = check(snapshot, profile).report  # the check run and estimate make (the from-line check is plot's own, below)
    errors = report.errors
    if from_line > 1:  # a resume line the compiler cannot start at is an error like any other
        resume = [d for d in snapshot.compile(from_line=from_line).finish() if d.code == "E010"]
        report.diagnostics.extend(resume)
        errors += len(resume)
    click.echo(TextFormatter().file(report), err=True, nl=False)  # exactly as `armctl lint` writes them
    if errors and not force:
        _fail(f"{errors} error{'s' if errors != 1 else ''}: nothing was drawn (--force draws it anyway)", EXIT_PROBLEMS)
    return report.diagnostics


def _build(snapshot, profile, from_line: int, diagnostics):
    from ..core.motion import MotionModel
    from .path import build_path

    statements = snapshot.compile(from_line=from_line)
    return build_path(statements, MotionModel(profile), snapshot.name, diagnostics, from_line=from_line)


def _render(path, output: str, fmt: str, view) -> None:
    try:
        if fmt == "html":
            from .html import write_html

            write_html(path, output, view or "3d")
        else:
            from .static import write_static

            write_static(path, output, fmt, view)
    except OSError as error:
        _fail(f"cannot write {output}: {error.strerror or error}")


def _summary(path, output: str) -> None:
    from .style import summary

    click.echo(f"wrote {output}: {summary(path)}, from the profile's fixed pose 0")
    if path.approximate:
        click.echo("joint moves are drawn through the profile's kinematics: approximate, not verified against your arm")
    if path.omitted:
        click.echo(f"{path.omitted} later segments were not drawn (more than {len(path.segments)})")
