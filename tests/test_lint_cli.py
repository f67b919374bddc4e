"""``armctl lint`` as a user and CI see it: formats, exit codes, paths, stdin, bad input.

The command object is invoked through a click group of our own, as armctl/ui/cli.py will
register it.  Every test runs in an empty working directory, so no armctl.toml from the
checkout changes the profile (the default profile, unless a test writes one).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from armctl.lint import RULES
from armctl.lint.command import lint

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "lint"
CLEAN = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 Z100\n"
WARNING = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F30\n"  # L203 only
# L101 on line 3: an error whatever the profile (L103 on the built-in profile's illustrative
# workspace is a warning, tests/test_lint_provenance.py)
ERROR = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG300 X260 Y10 Z150 R10\nG301 X250 Y0 Z150\n"

HEADLINE = re.compile(r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): (?P<code>[EL]\d{3}) .+$")
GITHUB = re.compile(
    r"^::(?P<kind>error|warning) file=(?P<file>[^,:]*),line=(?P<line>\d+),endLine=\d+,col=(?P<col>\d+),"
    r"endColumn=\d+,title=armctl (?P<code>[EL]\d{3})::(?P<message>[^\r\n]*)$"
)


@click.group()
def cli():
    """A stand-in for armctl's main group."""


cli.add_command(lint)


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def run(*args, input=None):
    return CliRunner().invoke(cli, ["lint", *map(str, args)], input=input, catch_exceptions=False)


def write(path: Path, text: str | bytes) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    return path


# --- the shipped example jobs ---------------------------------------------------------------------


def test_example_scripts_lint_clean_with_the_default_profile():
    result = run(ROOT / "scripts", "--strict")
    assert result.exit_code == 0, result.output
    assert re.search(r"All checks passed \(\d+ files checked\)", result.stdout)


def test_example_scripts_compile():
    from armctl.script import compile_file

    scripts = sorted((ROOT / "scripts").glob("*.txt"))
    assert len(scripts) >= 6
    for path in scripts:
        job = compile_file(path)
        assert sum(1 for _ in job) > 0 and job.ok, [str(d) for d in job.diagnostics]


def test_pick_and_place_takes_20_to_40_seconds_of_arm_time():
    estimate = pytest.importorskip("armctl.core.estimate")
    from armctl.core.motion import MotionModel
    from armctl.host.profile import default_profile
    from armctl.script import compile_file

    model = MotionModel(default_profile())
    commands = (s.command for s in compile_file(ROOT / "scripts" / "pick_and_place.txt"))
    result = estimate.estimate_commands(commands, model, model.initial_pose())
    assert 20 <= result.job_s <= 40


# --- formats --------------------------------------------------------------------------------------


def test_text_format_is_ruff_like(tmp_path):
    path = write(tmp_path / "job.txt", ERROR)
    result = run(path)
    assert result.exit_code == 1
    lines = result.stdout.splitlines()
    match = HEADLINE.match(lines[0])
    assert match and match.group("code", "line", "col") == ("L101", "3", "1")
    assert lines[2] == "3 | G301 X250 Y0 Z150" and lines[3] == "  | ^^^^"
    assert any(line.startswith("  = hint: ") for line in lines)
    assert lines[-1] == "Found 1 error in 1 of 1 file."


def test_json_format_is_one_array_with_the_promised_fields(tmp_path):
    write(tmp_path / "a.txt", ERROR)
    write(tmp_path / "b.txt", WARNING)
    write(tmp_path / "c.txt", CLEAN)
    result = run(tmp_path, "--format", "json")
    assert result.exit_code == 1
    records = json.loads(result.stdout)
    assert [(Path(r["file"]).name, r["line"], r["code"], r["severity"]) for r in records] == [
        ("a.txt", 3, "L101", "error"), ("b.txt", 1, "L203", "warning")]
    for record in records:
        assert {"file", "line", "column", "end_line", "end_column", "code", "severity", "message"} <= record.keys()
        assert record["end_line"] == record["line"] and record["end_column"] > record["column"]
    assert "Found 1 error and 1 warning in 2 of 3 files." in result.stderr


def test_json_format_when_clean_is_an_empty_array(tmp_path):
    result = run(write(tmp_path / "a.txt", CLEAN), "--format", "json")
    assert (result.exit_code, json.loads(result.stdout)) == (0, [])


def test_github_format_is_workflow_commands_and_a_summary(tmp_path):
    write(tmp_path / "a.txt", ERROR)
    write(tmp_path / "b.txt", WARNING)
    result = run(tmp_path, "--format", "github")
    lines = result.stdout.splitlines()
    commands = [GITHUB.match(line) for line in lines[:-1]]
    assert all(commands), lines
    assert [(m.group("kind"), m.group("code"), m.group("line")) for m in commands] == [
        ("error", "L101", "3"), ("warning", "L203", "1")]
    assert "%0Ahint: " in commands[0].group("message")  # the hint, on its own line in the annotation
    assert lines[-1] == "Found 1 error and 1 warning in 2 of 2 files."


def test_github_escaping():
    from armctl.lint.formatters import escape_data, escape_property, github_command
    from armctl.script import Diagnostic, SourceSpan

    assert escape_data("100% done\r\nnext") == "100%25 done%0D%0Anext"
    assert escape_property("C:\\jobs\\a,b.txt") == "C%3A\\jobs\\a%2Cb.txt"
    span = SourceSpan("dir,1/a:b.txt", 3, 2, 5, "G1 X1")
    command = github_command(Diagnostic(span, "L203", "warning", "50% slower: yes\nreally", "fix, then: go"))
    assert command.startswith("::warning file=dir%2C1/a%3Ab.txt,line=3,endLine=3,col=2,endColumn=5,title=armctl L203::")
    assert command.endswith("title=armctl L203::50%25 slower: yes%0Areally%0Ahint: fix, then: go")
    assert "\n" not in command


def test_statistics_count_per_code(tmp_path):
    write(tmp_path / "a.txt", WARNING + "G1 X260 F40\nG1 X500 F3000\n")
    result = run(tmp_path / "a.txt", "--statistics")
    assert "2  L203  [warning]  cartesian-speed-in-deg-s" in result.stdout
    assert "1  L103  [warning]  outside-workspace" in result.stdout  # on the illustrative workspace


def test_list_rules_prints_every_code_with_severity_and_rationale():
    result = run("--list-rules")
    assert result.exit_code == 0
    listed = {line.split()[0]: line.split()[1] for line in result.stdout.splitlines()}
    assert listed == {code: rule.severity for code, rule in RULES.items()}
    records = json.loads(run("--list-rules", "--format", "json").stdout)
    assert [r["code"] for r in records] == list(RULES) and all(r["rationale"] for r in records)


def test_docs_list_every_code():
    docs = (ROOT / "docs" / "lint.md").read_text(encoding="utf-8")
    documented = re.findall(r"^\| ([EL]\d{3}) \| (error|warning) \|", docs, re.M)
    assert documented == [(code, rule.severity) for code, rule in RULES.items()]


# --- selection ------------------------------------------------------------------------------------


def test_select_and_ignore_options(tmp_path):
    path = write(tmp_path / "a.txt", WARNING + "G1 X500\n")
    assert [r["code"] for r in json.loads(run(path, "--format", "json", "--select", "L2").stdout)] == ["L203"]
    assert [r["code"] for r in json.loads(run(path, "--format", "json", "--ignore", "L203,E").stdout)] == ["L103"]
    assert run(path, "--ignore", "L1", "--ignore", "L203").exit_code == 0


def test_inline_ignore_through_the_command(tmp_path):
    path = write(tmp_path / "a.txt", "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 X500 ; armctl: ignore[L103]\n")
    assert run(path).exit_code == 0


def test_unknown_code_is_a_usage_error(tmp_path):
    result = run(write(tmp_path / "a.txt", CLEAN), "--select", "Z9")
    assert result.exit_code == 2 and "unknown rule code or prefix 'Z9'" in result.stderr


@pytest.mark.parametrize("option, value", [("--select", ""), ("--select", ","), ("--ignore", " , ")])
def test_an_option_that_names_no_code_is_a_usage_error(tmp_path, option, value):
    # `--select ''` ran every rule, exit 0 (found by a review): a mistake taken for "all"
    result = run(write(tmp_path / "a.txt", CLEAN), option, value)
    assert result.exit_code == 2 and f"{option} names no rule code" in result.stderr, result.stderr


def test_an_unknown_code_in_armctl_toml_names_the_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    write(tmp_path / "armctl.toml", '[lint]\nselect = ["X9"]\n')
    result = run(write(tmp_path / "a.txt", CLEAN))
    assert result.exit_code == 2 and "armctl.toml: lint.select: unknown rule code or prefix 'X9'" in result.stderr, \
        result.stderr


def test_armctl_toml_sets_patterns_and_codes(tmp_path):
    write(tmp_path / "armctl.toml", '[lint]\ninclude = ["*.job"]\nexclude = ["old/*"]\nignore = ["L203"]\n')
    write(tmp_path / "jobs" / "a.job", WARNING)
    write(tmp_path / "jobs" / "old" / "b.job", ERROR)
    write(tmp_path / "jobs" / "c.txt", ERROR)
    result = run("jobs", "--format", "json")
    assert (result.exit_code, json.loads(result.stdout)) == (0, [])
    assert "1 file checked" in result.stderr


def test_bad_armctl_toml_is_exit_2(tmp_path):
    write(tmp_path / "armctl.toml", '[lint]\ninclude = "*.txt"\n')
    result = run(write(tmp_path / "a.txt", CLEAN))
    assert result.exit_code == 2 and "lint.include must be a list of strings" in result.stderr


# --- exit codes -----------------------------------------------------------------------------------


@pytest.mark.parametrize("text, strict, code", [
    (CLEAN, False, 0), (WARNING, False, 0), (WARNING, True, 1), (ERROR, False, 1), (ERROR, True, 1)])
def test_exit_codes(tmp_path, text, strict, code):
    result = run(write(tmp_path / "a.txt", text), *(["--strict"] if strict else []))
    assert result.exit_code == code


def test_no_paths_is_a_usage_error():
    result = run()
    assert result.exit_code == 2 and "give the scripts or directories to lint" in result.stderr


def test_bad_profile_is_exit_2(tmp_path):
    profile = write(tmp_path / "bad.toml", "[speed]\nmax_linear_mm_mins = 3\n")
    result = run(write(tmp_path / "a.txt", CLEAN), "--profile", profile)
    assert result.exit_code == 2 and "unknown key 'speed.max_linear_mm_mins'" in result.stderr
    result = run(tmp_path / "a.txt", "--profile", tmp_path / "missing.toml")
    assert result.exit_code == 2 and "file not found" in result.stderr


def test_profile_option_changes_the_checks(tmp_path):
    path = write(tmp_path / "a.txt", CLEAN + "G1 S2000\n")
    assert run(path).exit_code == 0
    result = run(path, "--profile", DATA / "profile.toml")
    assert result.exit_code == 1 and "L501" in result.stdout


# --- paths, stdin and bad input -------------------------------------------------------------------


def test_directories_are_searched_recursively_by_extension(tmp_path):
    for name in ("a.txt", "deep/b.arm", "deep/er/c.GCODE", "d.nc", "notes.md", ".hidden/e.txt", "deep/.git/f.txt"):
        write(tmp_path / "jobs" / name, WARNING)
    records = json.loads(run("jobs", "--format", "json").stdout)
    assert sorted(Path(r["file"]).relative_to("jobs").as_posix() for r in records) == [
        "a.txt", "d.nc", "deep/b.arm", "deep/er/c.GCODE"]


def test_a_file_named_twice_is_linted_once(tmp_path):
    path = write(tmp_path / "a.txt", WARNING)
    assert len(json.loads(run(path, tmp_path, "--format", "json").stdout)) == 1


def test_stdin(tmp_path):
    result = run("-", "--format", "json", "--stdin-filename", "piped.txt", input=ERROR)
    assert result.exit_code == 1
    assert [(r["file"], r["line"], r["code"]) for r in json.loads(result.stdout)] == [("piped.txt", 3, "L101")]
    assert run("-", input=CLEAN).exit_code == 0


def test_missing_file_is_exit_2_but_the_rest_is_still_linted(tmp_path):
    path = write(tmp_path / "a.txt", ERROR)
    result = run(tmp_path / "nope.txt", path)
    assert result.exit_code == 2
    assert "nope.txt: no such file or directory" in result.stderr
    assert "L101" in result.stdout
    assert result.stdout.splitlines()[-1] == "Found 1 error in 1 of 1 file. 1 path could not be read (see above)."


def test_directory_without_scripts_is_exit_2(tmp_path):
    write(tmp_path / "empty" / "readme.md", "# nothing to lint")
    result = run(tmp_path / "empty")
    assert result.exit_code == 2 and "no motion scripts here" in result.stderr
    assert result.stdout == "No scripts checked. 1 path could not be read (see above).\n"


def test_unreadable_file_is_exit_2(tmp_path):
    import os

    path = write(tmp_path / "secret.txt", CLEAN)
    path.chmod(0)
    if os.access(path, os.R_OK):  # running as root
        pytest.skip("root reads every file")
    result = run(path)
    assert result.exit_code == 2 and "cannot read" in result.stderr


@pytest.mark.parametrize("content, code, message", [
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00", "E011", "not UTF-8"),
    ("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000 ; Temp\xe9rature\n".encode("latin-1"), "E011", "byte 0xe9"),
    (b"; comment\n; a\x00b\n", "E011", "NUL byte"),
])
def test_binary_and_non_utf8_files_are_located_e011(tmp_path, content, code, message):
    result = run(write(tmp_path / "bad.txt", content))
    assert result.exit_code == 1
    assert HEADLINE.match(result.stdout.splitlines()[0]).group("code") == code
    assert message in result.stdout


@pytest.mark.parametrize("line", ["X" * 1_000_000, "G1 X1" + " " * 1_000_000 + "X2"])
def test_a_one_megabyte_line(tmp_path, line):
    path = write(tmp_path / "long.txt", line + "\n" + CLEAN)
    result = run(path, "--format", "json")
    assert result.exit_code == 1
    records = json.loads(result.stdout)
    assert ("E011", 1) in [(r["code"], r["line"]) for r in records]
    assert any("4096" in r["message"] for r in records if r["code"] == "E011")
    text = run(path).stdout  # the text format shows a window of the line, not a megabyte
    assert len(text) < 3000


def test_an_empty_file_is_a_warning(tmp_path):
    path = write(tmp_path / "empty.txt", b"")
    result = run(path)
    assert result.exit_code == 0
    assert "empty.txt:1:1: L403 the file is empty: it sends nothing to the arm" in result.stdout
    assert run(path, "--strict").exit_code == 1
