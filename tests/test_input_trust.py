"""Issue 10, the input half: what was checked is exactly what is sent, every input is bounded,
every script's expansion is bounded, and any failure mid-job takes the Ctrl-C path.

Runs go to ``sim://?clock=virtual`` (model time, immune to a loaded machine).  Endless inputs
and huge expansions run through the installed command in a fresh process, each bounded by a
subprocess timeout: a hang fails the test instead of hanging the suite.
"""

from __future__ import annotations

import errno
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from armctl.host import link as link_module
from armctl.ui.cli import main
from armctl.script import MAX_LINE_LENGTH, compile_text, read_script
from armctl.script.source import MAX_LINES_RUN

ARMCTL = [sys.executable, "-m", "armctl"]
START = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F6000\n"
JOB = START + "".join(f"G1 Y{y}\nG1 Z{140 - (k % 3) * 10}\n" for k, y in enumerate((40, -40, 60, -60, 20, -20, 0)))
EVIL = START + "G1 X500 Y400 Z-100\n" * 40  # lint rejects X500: it must never be sent
TIMEOUT_S = 20


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("ARMCTL_PORT", "")


def armctl(*args, stdin=None, input=None):
    return subprocess.run([*ARMCTL, *map(str, args)], capture_output=True, timeout=TIMEOUT_S, stdin=stdin,
                          input=input, env={**os.environ, "ARMCTL_PORT": ""})


def compiled_hex(text: str) -> list[str]:
    result = CliRunner().invoke(main, ["compile", "-"], input=text)
    assert result.exit_code == 0, result.output
    return result.stdout.split()


def logged_motion(log: Path) -> list[str]:
    records = [json.loads(line) for line in log.read_text().splitlines()]
    return [r["hex"] for r in records if r["dir"] == "tx" and "line" in r]


# --- 1. read once: the file changing under a run changes nothing sent --------------------------------


@pytest.mark.parametrize("how", ["replace", "edit in place"])
def test_a_script_changed_while_run_streams_sends_exactly_what_was_checked(tmp_path, monkeypatch, how):
    from armctl.ui import run_job

    script, log = tmp_path / "job.txt", tmp_path / "job.log"
    script.write_text(JOB)
    real_update, changed = run_job._Display.update, []

    def update(self, view):  # mid-job, after the first frame left
        real_update(self, view)
        if view.frames_sent == 1 and not changed:
            changed.append(True)
            if how == "replace":
                spare = tmp_path / "evil.txt"
                spare.write_text(EVIL)
                os.replace(spare, script)
            else:
                with open(script, "r+") as handle:
                    handle.write(EVIL)

    monkeypatch.setattr(run_job._Display, "update", update)
    result = CliRunner().invoke(main, ["run", str(script), "--no-live", "--port", "sim://?clock=virtual",
                                       "--log", str(log)])
    assert changed and script.read_text().startswith(EVIL[:60])  # the file really changed mid-job
    assert result.exit_code == 0, result.output
    assert logged_motion(log) == compiled_hex(JOB)
    assert "frames: 15 of 15 sent" in result.stdout


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(at_frame=st.integers(1, 14), new_text=st.sampled_from([EVIL, "", JOB[:70], "G1 X\x00\xff\n", JOB.replace("Y", "Z")]))
def test_whatever_the_file_becomes_and_whenever_the_frames_sent_are_the_checked_ones(tmp_path, at_frame, new_text):
    from armctl.ui import run_job

    script, log = tmp_path / "job.txt", tmp_path / "job.log"
    script.write_text(JOB)
    real_update = run_job._Display.update

    def update(self, view):
        real_update(self, view)
        if view.frames_sent == at_frame:
            script.write_bytes(new_text.encode("utf-8", "surrogateescape"))

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(run_job._Display, "update", update)
        result = CliRunner().invoke(main, ["run", str(script), "--no-live", "--port", "sim://?clock=virtual",
                                           "--log", str(log)])
    assert result.exit_code == 0, result.output
    assert logged_motion(log) == compiled_hex(JOB)


def test_run_and_estimate_read_stdin_once():
    ran = armctl("run", "-", "--dry-run", input=JOB.encode())
    assert ran.returncode == 0, ran.stderr
    assert [line.split()[1] for line in ran.stdout.decode().splitlines() if line.strip()[:1].isdigit()] == compiled_hex(JOB)
    estimated = armctl("estimate", "-", "--json", input=JOB.encode())
    assert estimated.returncode == 0, estimated.stderr
    assert json.loads(estimated.stdout)["frames"] == 15


def test_the_snapshot_gives_the_same_lines_on_every_pass(tmp_path):
    path = tmp_path / "job.txt"
    path.write_text(JOB)
    snapshot = read_script(str(path))
    path.write_text(EVIL)
    first = [s.command.encode() for s in snapshot.compile()]
    assert first == [s.command.encode() for s in snapshot.compile()] and len(first) == 15
    assert list(snapshot.lines()) == JOB.splitlines(keepends=True)


# --- 2. endless inputs: a clear message, bounded time and memory ------------------------------------


@pytest.mark.parametrize("command", [["lint"], ["compile"], ["estimate"], ["run", "--dry-run"]])
def test_dev_zero_as_a_script_is_a_binary_file(command):
    result = armctl(*command, "/dev/zero")
    assert result.returncode == 1, result.stderr
    assert b"E011 NUL byte" in result.stdout + result.stderr
    assert b"Traceback" not in result.stderr


@pytest.mark.parametrize("command", [["lint", "-"], ["compile", "-"], ["run", "--dry-run", "-"], ["decode", "-"]])
def test_an_endless_stdin_is_refused_at_the_limit(command):
    yes = subprocess.Popen(["yes", "G4 P1"], stdout=subprocess.PIPE)
    try:
        result = armctl(*command, stdin=yes.stdout)
    finally:
        yes.kill()
        yes.wait(timeout=TIMEOUT_S)
    assert result.returncode == 2, result.stderr
    assert b"<stdin>: longer than 128 MiB" in result.stderr
    assert b"Traceback" not in result.stderr


def test_decode_dev_zero_is_refused_before_it_is_read():
    # issue 22: where a file is meant, a device is refused before it is opened (stdin is the stream)
    result = armctl("decode", "/dev/zero")
    assert result.returncode == 2
    assert result.stderr.decode().strip() == "armctl: /dev/zero: a character device, not a regular file"


@pytest.mark.parametrize("command", [["estimate", "--profile", "/dev/zero", "JOB"], ["lint", "--profile", "/dev/zero", "JOB"],
                                     ["run", "--dry-run", "--profile", "/dev/zero", "JOB"]])
def test_a_profile_that_never_ends_is_refused(tmp_path, command):
    (tmp_path / "job.txt").write_text(JOB)
    result = armctl(*[tmp_path / "job.txt" if part == "JOB" else part for part in command])
    assert result.returncode == 2, result.stderr
    assert b"/dev/zero: a character device, not a regular file" in result.stderr  # issue 22: not opened
    (tmp_path / "huge.toml").write_bytes(b"#" * (1 << 20) + b"\n")  # a regular file past the bound
    result = armctl(*[tmp_path / "job.txt" if part == "JOB" else tmp_path / "huge.toml" if part == "/dev/zero" else part
                      for part in command])
    assert result.returncode == 2, result.stderr
    assert b"huge.toml: longer than 1 MiB" in result.stderr


def test_a_simulator_profile_that_never_ends_is_refused(tmp_path):
    (tmp_path / "job.txt").write_text(JOB)
    result = armctl("run", tmp_path / "job.txt", "--no-live", "--port", "sim://?clock=virtual&profile=/dev/zero")
    assert result.returncode != 0
    assert b"/dev/zero: a character device, not a regular file" in result.stderr and b"Traceback" not in result.stderr


# --- 3. bounded expansion ------------------------------------------------------------------------


def nested(depth: int, count: str, body: str = "G4 P1") -> str:
    opens = "".join(f"O<l{k}> repeat [{count}]\n" for k in range(depth))
    closes = "".join(f"O<l{k}> endrepeat\n" for k in reversed(range(depth)))
    return opens + body + "\n" + closes


# a literal count of 1e9 and 64 nested blocks of 2, through the same commands: tests/test_cli_properties_bounds.py
@pytest.mark.parametrize("text", ["#<n> = 1000000000\n" + nested(1, "#<n>", "#<i> = 1")], ids=["assignments only"])
@pytest.mark.parametrize("command", [["lint"], ["compile"], ["estimate"], ["run", "--dry-run"]])
def test_a_huge_expansion_is_one_located_error_before_anything_runs(tmp_path, text, command):
    path = tmp_path / "job.txt"
    path.write_text(text)
    result = armctl(*command, path)
    output = (result.stdout + result.stderr).decode()
    assert result.returncode == 1, output
    line = 2 if text.startswith("#") else 1
    assert f"job.txt:{line}:" in output and "E012" in output and "Traceback" not in output


@pytest.mark.parametrize("line", ["G4 P3" + "0" * 38, "G1 U3" + "0" * 38])
@pytest.mark.parametrize("command", [["estimate"], ["run", "--dry-run"], ["run", "--no-live", "--port", "sim://?clock=virtual"]])
def test_a_job_with_a_huge_motion_time_is_refused_before_anything_is_sent(tmp_path, line, command):
    path = tmp_path / "job.txt"
    path.write_text(START + line + "\n")
    result = armctl(*command, path)
    assert result.returncode == 1, result.stderr
    assert b"job.txt:2:1: E012 the job's motion time passes 24 hours here" in result.stderr
    assert b"nothing was sent to the arm" in result.stderr and b"ee31" not in result.stdout


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(depth=st.integers(1, 70), count=st.one_of(st.integers(0, 3), st.integers(10**5, 10**30)),
       body=st.integers(1, 3))
def test_expansion_is_counted_exactly_and_refused_past_the_limit(depth, count, body):
    # lines run: the repeat line once, then per pass its endrepeat and its body (an inner
    # block: its repeat line, then its own passes)
    per_pass = 1 + body
    for _ in range(min(depth, 64) - 1):
        per_pass = 2 + count * per_pass
    lines_run = 1 + count * per_pass
    assume(depth > 64 or lines_run <= 5000 or lines_run > MAX_LINES_RUN)  # keep each example fast
    job = compile_text(nested(depth, str(count), "\n".join(["G4 P1"] * body)))
    statements = sum(1 for _ in job)
    codes = [(d.code, d.span.line) for d in job.diagnostics]
    if depth > 64:
        assert ("E008", 65) in codes  # too deep: reported, never run
    elif lines_run > MAX_LINES_RUN:
        assert codes == [("E012", 1)] and statements == 0
    else:
        assert codes == [] and statements == count ** depth * body and job.lines_run == lines_run


def test_a_count_known_only_while_running_is_still_bounded():
    # the inner count is set inside the outer body: the running total stops it
    text = "#<n> = 0\nO<a> repeat [3]\n#<n> = [#<n> + 1500000]\nO<b> repeat [#<n>]\nG4 P1\nO<b> endrepeat\nO<a> endrepeat\n"
    job = compile_text(text)
    statements = sum(1 for _ in job)
    assert [d.code for d in job.diagnostics] == ["E012"] and statements <= MAX_LINES_RUN


# --- 4. compile -o -------------------------------------------------------------------------------


@pytest.mark.parametrize("alias", ["same", "hard link", "symlink"])
def test_compile_never_writes_over_its_own_script(tmp_path, alias):
    script = tmp_path / "job.txt"
    script.write_text(JOB)
    target = script
    if alias == "hard link":
        target = tmp_path / "link.txt"
        os.link(script, target)
    elif alias == "symlink":
        target = tmp_path / "link.txt"
        target.symlink_to(script)
    result = armctl("compile", script, "-o", target)
    assert result.returncode == 2
    assert b"it is the script itself" in result.stderr
    assert script.read_text() == JOB


def test_compile_o_writes_only_after_a_clean_check_and_leaves_no_temporary_file(tmp_path):
    out = tmp_path / "frames.hex"
    out.write_text("old\n")
    bad = tmp_path / "bad.txt"
    bad.write_text(JOB + "G1 X\n")
    result = CliRunner().invoke(main, ["compile", str(bad), "-o", str(out)])
    assert result.exit_code == 1 and out.read_text() == "old\n"
    good = tmp_path / "good.txt"
    good.write_text(JOB)
    result = CliRunner().invoke(main, ["compile", str(good), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert out.read_text().split() == compiled_hex(JOB)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.txt", "frames.hex", "good.txt"]
    fresh = tmp_path / "fresh.hex"
    assert CliRunner().invoke(main, ["compile", str(good), "-o", str(fresh)]).exit_code == 0
    umask = os.umask(0)
    os.umask(umask)
    assert fresh.stat().st_mode & 0o777 == 0o666 & ~umask  # as open() would create it, not mkstemp's 0600


# --- 5. a --log that fails mid-job takes the Ctrl-C path ------------------------------------------------


class FailingLog:
    """A log file that raises ENOSPC after ``good`` writes."""

    name = "job.log"

    def __init__(self, good: int) -> None:
        self.good, self.lines = good, []

    def write(self, text: str) -> int:
        if len(self.lines) >= self.good:
            raise OSError(errno.ENOSPC, "No space left on device")
        self.lines.append(text)
        return len(text)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_a_log_that_fails_mid_job_stops_the_job_like_ctrl_c(tmp_path, monkeypatch):
    from armctl.ui import run_job

    writes: list[bytes] = []
    real_write = link_module.Link.write

    def write(self, frame):
        writes.append(bytes(frame))
        return real_write(self, frame)

    monkeypatch.setattr(link_module.Link, "write", write)
    log = FailingLog(good=60)  # status frames and the first frames, then the disk is full
    monkeypatch.setattr(run_job, "_open_log", lambda path: log)
    script = tmp_path / "job.txt"
    script.write_text(JOB)
    result = CliRunner().invoke(main, ["run", str(script), "--no-live", "--port", "sim://?clock=virtual",
                                       "--log", "job.log"])
    assert result.exit_code == 1, result.output
    assert "the log job.log could not be written" in result.stderr
    assert "sending the abort sequence (pause)" in result.stderr
    assert writes and writes[-1].hex().startswith("fc1e0302")  # the pause toggle went out last
    motion = [w for w in writes if w[0] == 0xEE]
    assert 0 < len(motion) < 15  # it stopped feeding
    assert "last line sent:" in result.stdout and "resume with: armctl run" in result.stdout
    assert "stopped: failed" in result.stderr


def test_a_full_disk_under_the_log_stops_the_job_with_exit_1():
    # /dev/full: every write fails with ENOSPC, as on a full disk; the installed command
    result = armctl("run", Path(__file__).parent / "data" / "scripts_cli" / "short_job.txt", "--no-live",
                    "--port", "sim://?clock=virtual", "--log", "/dev/full")
    assert result.returncode == 1, result.stderr
    err = result.stderr.decode()
    # the job's first record failed: nothing of the job is queued, so no abort sequence goes either
    assert "the log /dev/full could not be written" in err and "before the first frame, nothing was sent" in err
    assert "resume with: armctl run" in result.stdout.decode() and "Traceback" not in err


# --- 6. messages ---------------------------------------------------------------------------------


@pytest.mark.parametrize("length", [4097, 20_009, 1 << 20])
def test_e011_gives_a_long_lines_real_length(tmp_path, length):
    path = tmp_path / "job.txt"
    path.write_bytes(b"G4 P1 ;" + b"x" * (length - 7) + b"\nG4 P1\n")
    [diagnostic] = read_script(str(path)).compile().finish()
    assert diagnostic.code == "E011"
    assert diagnostic.message == f"line is {length} characters long; a statement has at most {MAX_LINE_LENGTH}"


def test_infinity_times_zero_is_not_a_number_not_too_large():
    huge = "1" + "0" * 400  # a literal beyond a double: infinity
    [diagnostic] = [d for d in compile_text(f"#<a> = [{huge} * 0]\n").finish() if d.code == "E009"]
    assert "is not a number (NaN)" in diagnostic.message and "too large" not in diagnostic.message


# --- lint's cost follows the text: a pass that repeats the last one is not run again ----------------


def test_lint_stops_a_loop_once_a_pass_repeats_the_one_before():
    from armctl.script import compile_lines

    loop = START + "O<a> repeat [600000]\nG1 Y10\nG1 Y-10 S1500\nO<a> endrepeat\n"
    job = compile_lines(loop.splitlines(), skip_repeats=True)
    # pass 2 differs from pass 1 (its first move carries S1500), pass 3 repeats pass 2: stop
    assert sum(1 for _ in job) == 1 + 3 * 2 and job.diagnostics == []
    assert job.lines_run < 20
    relative = START + "G91\nO<a> repeat [50]\nG1 Y1\nO<a> endrepeat\n"  # each pass moves on: all run
    assert sum(1 for _ in compile_lines(relative.splitlines(), skip_repeats=True)) == 1 + 50
    paused = START + "O<a> repeat [5]\nPAUSE\nO<a> endrepeat\n"  # the pause state alternates: all run
    assert sum(1 for _ in compile_lines(paused.splitlines(), skip_repeats=True)) == 1 + 5


BODY_LINES = ["G1 Y10", "G1 Y-10 S1500", "G91", "G90", "G1 X5", "G1 X600", "PAUSE", "G4 P10", "#<i> = [#<i> + 1]",
              "G1 Y#<i>", "G6 J1=10 J2=0 J3=0 J4=0 J5=0 J6=0 F20", "G1 F30", "G1 Z[200 / #<z>]", "#<z> = 0"]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(body=st.lists(st.sampled_from(BODY_LINES), min_size=1, max_size=4),
       inner=st.lists(st.sampled_from(BODY_LINES), max_size=2), count=st.integers(0, 6), inner_count=st.integers(0, 4))
def test_skipping_repeated_passes_never_changes_what_lint_reports(body, inner, count, inner_count):
    from armctl.lint import engine, lint_lines
    from armctl.host.profile import default_profile

    script = ("#<i> = 0\n#<z> = 1\n" + START + f"O<a> repeat [{count}]\n" + "\n".join(body) + "\n"
              + (f"O<b> repeat [{inner_count}]\n" + "\n".join(inner) + "\nO<b> endrepeat\n" if inner else "")
              + "O<a> endrepeat\nG1 Z140\n")
    skipped = lint_lines(script.splitlines(), "job.txt", default_profile())
    real = engine.compile_lines
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(engine, "compile_lines", lambda *a, **k: real(*a, **{**k, "skip_repeats": False}))
        every_pass = lint_lines(script.splitlines(), "job.txt", default_profile())
    assert skipped.diagnostics == every_pass.diagnostics
    assert skipped.counts == every_pass.counts


@pytest.mark.parametrize("mode", ["G90", "G91"])
def test_every_line_counts_once_toward_the_expansion_bound(mode):
    """A plain line the fast path hands on to the general one (G91, here) is still one line run."""
    from armctl.script import compile_text

    job = compile_text(f"{mode}\n" + "G1 X1 Y1 Z1 A180 B0 C0 F100\n" * 3)
    list(job)
    assert job.lines_run == 4
