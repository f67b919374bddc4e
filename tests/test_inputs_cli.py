"""Issue 22: options and streams that crashed a command — one line naming them, exit 2.

``--port 'sim://['`` (urllib's "Invalid IPv6 URL", a ValueError traceback) on every command
that opens a port, and in ARMCTL_PORT and ``sim --url``; stdout closed (``>&-``: Python starts
with ``sys.stdout`` None) — ``compile`` and ``run --json`` died of AttributeError, while ``lint``,
``decode`` and ``estimate`` lost their output and exited 0.  Through the installed command in a
fresh process.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ARMCTL = str(Path(sys.executable).with_name("armctl"))
JOB = "scripts/pick_and_place.txt"
TIMEOUT_S = 60
ENV = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}


def only_line(stderr: str) -> str:
    assert "Traceback" not in stderr, stderr
    lines = [line for line in stderr.splitlines() if line.strip() and "using the built-in simulator" not in line]
    assert len(lines) == 1, stderr
    return lines[0]


@pytest.mark.parametrize("args", [["run", JOB, "--no-live", "--port", "sim://["], ["status", "--once", "--port", "sim://["],
                                  ["probe", "--port", "sim://["], ["sim", "--pty", "--url", "sim://["],
                                  ["run", JOB, "--port", "sim://[x]?clock=virtual"]], ids=" ".join)
def test_a_sim_url_that_is_no_url_is_named(args):
    done = subprocess.run([ARMCTL, *args], capture_output=True, text=True, timeout=TIMEOUT_S, cwd=ROOT, env=ENV,
                          stdin=subprocess.DEVNULL)
    assert done.returncode == 2, done.stderr
    line = done.stderr.strip().splitlines()[-1]
    assert "Traceback" not in done.stderr
    assert line.startswith(("armctl: --port: 'sim://[", "armctl: --url: 'sim://[")), line


def test_armctl_port_that_is_no_url_is_named():
    done = subprocess.run([ARMCTL, "status", "--once"], capture_output=True, text=True, timeout=TIMEOUT_S, cwd=ROOT,
                          env={**ENV, "ARMCTL_PORT": "sim://["})
    assert done.returncode == 2 and only_line(done.stderr).startswith("armctl: ARMCTL_PORT: 'sim://['"), done.stderr


@pytest.mark.parametrize("args", [["compile", JOB], ["run", "--json", JOB, "--port", "sim://?clock=virtual"], ["lint", JOB],
                                  ["decode", "-"], ["estimate", JOB], ["estimate", "--json", JOB], ["config", "--json"]],
                         ids=" ".join)
def test_a_closed_stdout_is_exit_2_before_anything_is_done(tmp_path, args):
    log = tmp_path / "job.log"
    extra = ["--log", str(log)] if args[0] == "run" else []
    done = subprocess.run(["sh", "-c", '"$@" >&-', "sh", ARMCTL, *args, *extra], capture_output=True, text=True,
                          timeout=TIMEOUT_S, cwd=ROOT, env=ENV, stdin=subprocess.DEVNULL)
    assert done.returncode == 2, done.stderr
    assert only_line(done.stderr) == ("armctl: cannot write the output: standard output is closed (to drop it, "
                                      "redirect it to /dev/null)")
    assert not log.exists()  # refused before the port (and the log) opened: nothing sent


def test_the_sim_url_parse_names_the_url():
    from armctl.sim.protocol_sim import SimOptionError, parse_sim_url

    with pytest.raises(SimOptionError, match=r"'sim://\[' is not a URL"):
        parse_sim_url("sim://[")


@pytest.mark.parametrize("args", [["compile", JOB], ["lint", JOB], ["estimate", JOB]], ids=" ".join)
def test_a_read_only_stdout_is_exit_2_before_anything_is_done(args):
    done = subprocess.run(["sh", "-c", '"$@" 1</dev/null', "sh", ARMCTL, *args], capture_output=True, text=True,
                          timeout=TIMEOUT_S, cwd=ROOT, env=ENV, stdin=subprocess.DEVNULL)
    assert done.returncode == 2, done.stderr
    assert only_line(done.stderr) == ("armctl: cannot write the output: standard output is open for reading only "
                                      "(to drop it, redirect it to /dev/null)")
