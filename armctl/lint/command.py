"""The ``armctl lint`` click command: options in, exit code out, no checking logic here.

Strategy: parse the options and the ``[lint]`` table of armctl.toml, load the profile, then for
each target from armctl/lint/paths.py lint it (armctl/lint/engine.py) and write what its
formatter returns straight away, so output streams file by file.  Only click is imported at
module level; everything heavy is imported inside the command, keeping ``armctl --help`` fast.
armctl/ui/cli.py registers the command object ``lint`` with ``main.add_command(lint)``.

Exit codes: 0 no errors (warnings allowed unless --strict); 1 problems found; 2 a usage error,
a bad profile or armctl.toml, or a path that cannot be read (missing, unreadable, a directory
holding no script) — the other paths are still linted and reported.
"""

from __future__ import annotations

import click

from ..errors import EXIT_OK, EXIT_PROBLEMS, EXIT_USAGE

CONFIG_KEYS = ("include", "exclude", "select", "ignore")


def _codes(values: tuple[str, ...]) -> list[str]:
    """``--select E004,L1 --select L2`` → ['E004', 'L1', 'L2']."""
    return [code for value in values for code in value.split(",") if code.strip()]


@click.command(name="lint")
@click.argument("paths", nargs=-1, metavar="[PATH|-]...")
@click.option("--format", "fmt", type=click.Choice(["text", "json", "github"]), default="text", show_default=True,
              help="text: ruff-like, with the source line and a caret; json: one array of objects; "
                   "github: workflow commands that annotate a pull request.")
@click.option("--json", "as_json", is_flag=True, help="The same as --format json (armctl's one JSON spelling).")
@click.option("--select", multiple=True, metavar="CODES",
              help="Report only these codes or prefixes (comma-separated, repeatable): --select E,L1.")
@click.option("--ignore", multiple=True, metavar="CODES", help="Do not report these codes or prefixes: --ignore L203.")
@click.option("--strict", is_flag=True, help="Warnings fail the run too (exit 1).")
@click.option("--statistics", is_flag=True, help="After the findings, count them per code.")
@click.option("--profile", "profile_path", metavar="FILE",
              help="Arm profile (TOML). Default: armctl.toml's [profile] (or its path), else the packaged default.")
@click.option("--stdin-filename", metavar="NAME", help="The name to report for - (standard input).")
@click.option("--list-rules", is_flag=True, help="Print every code with its severity and rationale, then exit.")
@click.pass_context
def lint(ctx: click.Context, paths, fmt, as_json, select, ignore, strict, statistics, profile_path, stdin_filename, list_rules):
    """Check motion scripts against the language and the arm profile before anything moves.

    PATH is a script, a directory (searched recursively for *.txt *.arm *.gcode *.nc, or
    [lint] include = [...] in armctl.toml) or - for standard input. A line ending with
    `; armctl: ignore[CODE]` is not reported for CODE. Exit status: 0 clean (warnings allowed
    unless --strict), 1 problems found, 2 usage error or unreadable input.
    """
    from ..errors import ConfigError, ProfileError
    from .registry import UnknownCode

    if as_json:
        if fmt not in ("text", "json") or (fmt == "text" and ctx.get_parameter_source("fmt") != click.core.ParameterSource.DEFAULT):
            _fail(ctx, f"--json is --format json: it cannot be combined with --format {fmt}")
        fmt = "json"
    if list_rules:
        click.echo(_rules_listing(fmt), nl=False)
        return
    if not paths:
        raise click.UsageError("give the scripts or directories to lint, or - for standard input")
    try:
        config = _config()
        selection = _selection(select, ignore, config)
        from ..host.calibration import arm_profile

        profile = arm_profile(profile_path)  # the configured port's arm
    except (ConfigError, ProfileError, UnknownCode, ValueError) as error:
        _fail(ctx, str(error))
    ctx.exit(_run(paths, fmt, selection, strict, statistics, profile, stdin_filename, config))


def _run(paths, fmt, selection, strict, statistics, profile, stdin_filename, config) -> int:
    from dataclasses import replace

    from ..ui.output import quiet
    from .formatters import FORMATTERS, Summary, statistics_lines, summary_line
    from .paths import DEFAULT_INCLUDE, expand

    formatter, summary = FORMATTERS[fmt](), Summary()
    for target in expand(paths, config.get("include", DEFAULT_INCLUDE), config.get("exclude", ())):
        if target.problem:
            summary.unreadable += 1
            click.echo(f"armctl lint: {_safe(target.problem)}", err=True)
            continue
        report = _lint_target(target, profile, selection, stdin_filename)
        if report is None:
            summary.unreadable += 1
            continue
        summary.add(report)
        if fmt != "json" and quiet():  # -q: errors only (the summary still counts the warnings)
            report = replace(report, diagnostics=[d for d in report.diagnostics if d.severity == "error"])
        _write(formatter.file(report))
    table = "".join(line + "\n" for line in statistics_lines(summary.severities)) if statistics else ""
    if fmt == "json":  # stdout stays one JSON document
        _write(formatter.close(summary))
        click.echo(table + summary_line(summary), err=True)
    else:
        _write(table)
        _write(formatter.close(summary))
    if summary.unreadable:
        return EXIT_USAGE
    return EXIT_PROBLEMS if summary.errors or (strict and summary.warnings) else EXIT_OK


def _lint_target(target, profile, selection, stdin_filename):
    """The FileReport for one target, or None (reported on stderr) when it cannot be read.

    Read once and bounded (armctl/host/inputs.py).  A regular file streams line by line, so lint's
    memory stays flat however long the script (its size is checked first, and the stream is
    bounded too, in case it grows); stdin, a pipe or a device is read whole into a snapshot,
    which stops at the first NUL (``/dev/zero``) or at the limit (``yes |``) at once.
    """
    import os
    import stat
    import sys

    from ..host.inputs import MAX_INPUT_BYTES, InputTooLarge, read_bounded
    from ..script import ScriptSnapshot, iter_lines, read_script
    from .engine import lint_lines

    name = stdin_filename or "<stdin>" if target.is_stdin else target.path
    try:
        if target.is_stdin:
            stream = getattr(sys.stdin, "buffer", sys.stdin)
            return lint_lines(read_script("-", stdin=stream).lines(), name, profile, selection)
        with open(target.path, "rb") as stream:
            info = os.fstat(stream.fileno())
            if not stat.S_ISREG(info.st_mode):
                snapshot = ScriptSnapshot(name, read_bounded(stream, target.path, stop_at_nul_line=True))
                return lint_lines(snapshot.lines(), name, profile, selection)
            if info.st_size > MAX_INPUT_BYTES:
                raise InputTooLarge.beyond(target.path, MAX_INPUT_BYTES)
            return lint_lines(iter_lines(stream, MAX_INPUT_BYTES, target.path), name, profile, selection)
    except OSError as error:
        click.echo(f"armctl lint: cannot read {_safe(target.path)}: {error.strerror or error}", err=True)
        return None
    except InputTooLarge as error:
        click.echo(f"armctl lint: {_safe(str(error))}", err=True)
        return None


def _config() -> dict:
    """The ``[lint]`` table of the nearest armctl.toml (else the user's), checked (``check_lint_table``)."""
    from ..host.profile import load_config

    config = load_config()
    table = config.values.get("lint", {})
    check_lint_table(table, config.path_of("lint"))
    return table


def check_lint_table(table: dict, path) -> None:
    """A ``[lint]`` table's keys and codes checked (ValueError naming ``path``): lint reads it so,
    and ``armctl config`` checks it so."""
    from ..host.profile import unknown_key_hint

    for key, value in table.items():
        if key not in CONFIG_KEYS:
            raise ValueError(f"{path}: unknown key 'lint.{key}'{unknown_key_hint(key, CONFIG_KEYS)}")
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise ValueError(f"{path}: lint.{key} must be a list of strings")
        if key in ("select", "ignore"):
            from .registry import UnknownCode, check_prefixes

            try:
                check_prefixes(value)
            except UnknownCode as error:  # named where it is written: the file, not the command line
                raise ValueError(f"{path}: lint.{key}: {error}") from None


def _selection(select, ignore, config):
    """CLI --select replaces armctl.toml's select; --ignore adds to its ignore."""
    from .registry import Selection, UnknownCode

    for option, given in (("--select", select), ("--ignore", ignore)):
        if given and not _codes(given):  # `--select ''` read as "every rule" would hide a mistake
            raise UnknownCode(f"{option} names no rule code: give codes or prefixes (E004, L1, ALL), or leave it out")
    chosen = _codes(select) if select else config.get("select", [])
    return Selection.of(chosen, [*config.get("ignore", []), *_codes(ignore)])


def _rules_listing(fmt: str) -> str:
    import json

    from .registry import LINT_RULES, RULES, rule_name

    if fmt == "json":
        records = [{"code": code, "severity": r.severity, "name": rule_name(code), "rationale": r.summary}
                   for code, r in RULES.items()]
        return json.dumps(records, indent=2, ensure_ascii=False) + "\n"
    # the language's rationales already start with their name ("syntax: …")
    return "".join(f"{code}  {r.severity:<7}  {f'{LINT_RULES[code].name}: ' if code in LINT_RULES else ''}{r.summary}\n"
                   for code, r in RULES.items())


def _safe(text: str) -> str:
    """Undecodable file-name bytes (lone surrogates) as U+FFFD, so any terminal can print them."""
    return text if text.isascii() else text.encode("utf-8", "replace").decode("utf-8")


def _write(text: str) -> None:
    if text:
        click.echo(_safe(text), nl=False)


def _fail(ctx: click.Context, message: str):
    click.echo(f"armctl lint: {_safe(message)}", err=True)
    ctx.exit(EXIT_USAGE)
