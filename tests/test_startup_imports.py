"""Start-up (issue 13): a command loads only what it uses.  ``armctl lint`` and ``armctl
compile`` of a script whose lines the fast paths read never import Lark, the status frames
(armctl/core/status_frames.py) or the streamer; a line only Lark reads loads Lark, and reading the
arm's status loads the status frames.  Checked in fresh processes (what a user's start costs),
by module names, not by timing."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

# Runs armctl's CLI in this fresh process, then prints which of the watched modules it imported.
PROBE = """
import json, sys
from armctl.ui.cli import main
try:
    main(sys.argv[1:], standalone_mode=False)
except SystemExit:
    pass
watched = ("lark", "armctl.core.status_frames", "armctl.core.streamer", "platformdirs", "importlib.resources")
print(json.dumps({name: name in sys.modules for name in watched}), file=sys.stderr)
"""

SCRIPT = "#<z> = 150\nG1 X[200 + 20] Y0 Z#<z> A180 B0 C0 F3000 S1000\nG1 X205 Y-36 Z147\n"


def loaded(tmp_path, *args: str) -> dict:
    done = subprocess.run([sys.executable, "-c", PROBE, *args], capture_output=True, text=True, timeout=60,
                          cwd=tmp_path, env={"PATH": "/usr/bin:/bin", "HOME": str(tmp_path)})
    return json.loads(done.stderr.strip().splitlines()[-1])


@pytest.mark.parametrize("command", [["lint"], ["compile"]])
def test_lint_and_compile_of_a_plain_script_load_no_parser_generator_and_no_status_frames(tmp_path, command):
    (tmp_path / "job.txt").write_text(SCRIPT)
    modules = loaded(tmp_path, *command, "job.txt")
    assert modules == dict.fromkeys(modules, False)


def test_a_line_only_lark_reads_loads_it(tmp_path):
    (tmp_path / "job.txt").write_text(SCRIPT + "RESET\n")
    assert loaded(tmp_path, "lint", "job.txt")["lark"]
    (tmp_path / "bad.txt").write_text("G1 X[1\n")
    assert loaded(tmp_path, "compile", "bad.txt")["lark"]


def test_decode_loads_the_status_frames(tmp_path):
    (tmp_path / "frames.bin").write_bytes(bytes.fromhex("ce000000000000" + "00cf"))
    assert loaded(tmp_path, "decode", "frames.bin")["armctl.core.status_frames"]
