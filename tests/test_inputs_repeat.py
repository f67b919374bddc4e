"""Issue 22: ``compile`` of a 282-byte script with an unclosed outer repeat of a huge count took
9 s (a 1 KB variant 54 s) where ``lint`` refused it in 0.15 s: at the end of the file the
unclosed block is reported (E008) and then run, pass after pass, for frames nobody would write.
Now a compilation with an error runs repeats as lint's check does (a pass that repeats the last
one ends the block): one check path, the same work.  Speed is not timed here (the machine is
shared): the work is counted — the lines the compiler ran.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from armctl.lint import lint_lines
from armctl.host.profile import default_profile
from armctl.script import compile_text

ARMCTL = [sys.executable, "-m", "armctl"]
START = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F6000\n"
UNCLOSED = {
    "one line": START + "O1 repeat [999990]\nG1 X250 Y0 Z150 A180 B0 C0 S1000 F6000\n",
    "two lines": START + "O1 repeat [666000]\nG1 X250 Y0 Z150\nG1 X240 Y10 Z150\n",
    "nested, closed inside": START + "O1 repeat [99999]\nO2 repeat [6]\nG1 X250 Y0 Z150\nG1 X240 Y10 Z150\nO2 endrepeat\n",
    "an error inside": START + "O1 repeat [999990]\nG1 X250 Y0 Z150\nG1 X240 Y10 Z150 Q7\n",
}


@pytest.mark.parametrize("text", UNCLOSED.values(), ids=UNCLOSED.keys())
def test_compile_does_the_work_lint_does(text):
    compilation = compile_text(text, "job.txt")
    frames = list(compilation)
    assert compilation.error_count and frames is not None
    assert compilation.lines_run < 200, compilation.lines_run  # was about 2,000,000: every pass of the block
    lint = lint_lines(text.splitlines(keepends=True), "job.txt", default_profile())
    errors = sorted((d.code, d.span.line, d.span.column) for d in lint.diagnostics if d.severity == "error")
    found = sorted((d.code, d.span.line, d.span.column) for d in compilation.diagnostics if d.is_error)
    assert ("E008", 2, 1) in found and set(found) <= set(errors)  # lint adds its own (E012: 24 hours of motion)


def test_a_good_repeat_still_compiles_every_pass():
    text = START + "O1 repeat [1000]\nG1 X250 Y0 Z150\nG1 X240 Y10 Z150\nO1 endrepeat\n"
    compilation = compile_text(text, "job.txt")
    assert len(list(compilation)) == 1 + 2000 and compilation.error_count == 0


def test_the_installed_compile_refuses_it_as_lint_does(tmp_path):
    path = tmp_path / "job.txt"
    path.write_text(UNCLOSED["one line"])
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    compiled = subprocess.run([*ARMCTL, "compile", path], capture_output=True, text=True, timeout=60, env=env)
    linted = subprocess.run([*ARMCTL, "lint", path], capture_output=True, text=True, timeout=60, env=env)
    assert compiled.returncode == linted.returncode == 1, (compiled.stderr, linted.stdout)
    assert compiled.stdout == "" and "job.txt:2:1: E008 O1 repeat is never closed" in compiled.stderr
    assert "job.txt:2:1: E008 O1 repeat is never closed" in linted.stdout + linted.stderr
