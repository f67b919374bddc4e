"""Issue 26 item 3: ``-q``/``-v`` after the subcommand mean what they mean before it, through
the installed command in a fresh process and in-process (click's runner)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main

ARMCTL = Path(sys.executable).with_name("armctl")
VIRTUAL = "sim://?clock=virtual"
BANNER = "using the built-in simulator"


def armctl(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    return subprocess.run([str(ARMCTL), *args], capture_output=True, text=True, timeout=50, cwd=cwd, env=env)


@pytest.fixture
def job(tmp_path):
    path = tmp_path / "job.txt"
    path.write_text("G4 P100\n")
    return path


@pytest.mark.timeout(60)
@pytest.mark.parametrize("where", ["before", "after"])
def test_quiet_before_or_after_the_subcommand(tmp_path, job, where):
    args = ["run", str(job), "--no-live", "--port", VIRTUAL]
    done = armctl(*(["-q", *args] if where == "before" else [*args, "-q"]), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert BANNER not in done.stderr and done.stdout.splitlines()[-1].startswith("finished")


@pytest.mark.timeout(60)
def test_verbose_after_the_subcommand_logs_the_pacing(tmp_path, job):
    done = armctl("run", str(job), "--no-live", "--port", VIRTUAL, "--verbose", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "evidence" in done.stderr


@pytest.mark.timeout(60)
@pytest.mark.parametrize("args", [["-v", "lint", "{job}", "-q"], ["lint", "{job}", "-q", "-v"]])
def test_both_is_a_usage_error_wherever_they_are(tmp_path, job, args):
    done = armctl(*(a.format(job=job) for a in args), cwd=tmp_path)
    assert done.returncode == 2 and "choose -v or -q" in done.stderr


def test_in_process_each_invocation_starts_unquiet(job):
    runner = CliRunner()
    quiet = runner.invoke(main, ["status", "--once", "--port", VIRTUAL, "-q"])
    assert quiet.exit_code == 0, quiet.output
    assert BANNER not in quiet.stderr
    loud = runner.invoke(main, ["status", "--once", "--port", VIRTUAL])
    assert BANNER in loud.stderr


def test_every_command_takes_them_after():
    def commands(group):
        for command in group.commands.values():
            yield from commands(command) if hasattr(command, "commands") else [command]

    for command in commands(main):
        opts = {name for param in command.params for name in getattr(param, "opts", ())}
        assert {"-q", "-v"} <= opts, command.name
