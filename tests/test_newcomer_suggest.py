"""Issue 26 item 4: "did you mean" for script typos — statements, codes and words — in lint
and every command that checks a script (the compiler words the diagnostic once)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from armctl.script import compile_text
from armctl.script.suggest import keyword

ARMCTL = Path(sys.executable).with_name("armctl")
REST = " Y0 Z200 A180 B0 C0 S1500 F3000"
CASES = [
    ("PASUE", "E002", "(did you mean PAUSE?)"),
    ("reste", "E002", "(did you mean RESET?)"),
    ("POES 1", "E002", "(did you mean POSE?)"),
    ("Gl X200" + REST, "E001", "(did you mean G1?)"),
    ("G1 X25O" + REST, "E001", "(did you mean X250?)"),
    ("G1 XI00" + REST, "E001", "(did you mean X100?)"),
    ("G4 500", "E001", "(did you mean G4 P500?)"),
]


def _errors(text: str):
    compilation = compile_text(text + "\n", "t.txt")
    list(compilation)
    return [d for d in compilation.diagnostics if d.is_error]


@pytest.mark.parametrize("line, code, suggestion", CASES)
def test_compiler_suggests(line, code, suggestion):
    errors = _errors(line)
    assert errors[0].code == code and errors[0].message.endswith(suggestion), errors


@pytest.mark.parametrize("line", ["XYZZY", "G1 X 100" + REST, "G1 200", "G7 X1", "FOO BAR"])
def test_no_suggestion_when_no_repair_is_checked(line):
    assert "did you mean" not in _errors(line)[0].message


def test_keyword_matches_only_close_spellings():
    assert keyword("PAUS") == "PAUSE" and keyword("reset connectr") == "RESET CONNECTOR"
    assert keyword("HELLO") is None


def armctl(*args: str, cwd: Path, stdin: str | None = None) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    return subprocess.run([str(ARMCTL), *args], capture_output=True, text=True, timeout=50, cwd=cwd, env=env, input=stdin)


@pytest.mark.timeout(120)
def test_every_command_that_checks_a_script_suggests(tmp_path):
    script = tmp_path / "job.txt"
    script.write_text("G1 X200" + REST + "\nPASUE\nG4 500\nG1 X25O\n")
    suggestions = ["did you mean PAUSE?", "did you mean G4 P500?", "did you mean X250?"]
    lint = armctl("lint", "--json", str(script), cwd=tmp_path)
    assert lint.returncode == 1
    messages = [d["message"] for d in json.loads(lint.stdout)]
    assert all(any(s in m for m in messages) for s in suggestions), messages
    for args in (["lint", str(script)], ["compile", str(script)], ["estimate", str(script)],
                 ["run", str(script), "--port", "sim://?clock=virtual", "--no-live"]):
        done = armctl(*args, cwd=tmp_path)
        assert done.returncode == 1 and all(s in done.stdout + done.stderr for s in suggestions), (args, done.stderr)
