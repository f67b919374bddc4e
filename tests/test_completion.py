"""``armctl completion bash|zsh|fish``: the script click itself prints, through the installed
command in a fresh process and in-process; an unknown shell is a usage error (exit 2); the
printed script makes a real bash complete armctl's commands."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from click.shell_completion import get_completion_class
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.ui.completion import SHELLS, complete_var

# The console script pip installed beside this interpreter (the editable install of the suite's
# virtualenv): what a user runs, with the environment a user has.
INSTALLED = Path(sys.executable).with_name("armctl")


def installed(*args: str, env: dict | None = None, cwd: Path) -> subprocess.CompletedProcess:
    assert INSTALLED.exists(), f"the armctl command is not installed beside {sys.executable}"
    # the completion variables of the test runner's own shell must not leak into the child
    base = {k: v for k, v in os.environ.items() if not k.endswith("_COMPLETE") and not k.startswith("COMP_")}
    return subprocess.run([str(INSTALLED), *args], capture_output=True, text=True, cwd=cwd,
                          env={**base, **(env or {})}, timeout=60)


def test_the_variable_is_the_one_click_derives_for_the_command():
    assert complete_var() == "_ARMCTL_COMPLETE"
    assert complete_var("armctl-x") == "_ARMCTL_X_COMPLETE"


@pytest.mark.parametrize("shell", SHELLS)
def test_the_command_prints_what_click_prints_for_the_installed_command(shell, tmp_path):
    ours = installed("completion", shell, cwd=tmp_path)
    clicks = installed(env={"_ARMCTL_COMPLETE": f"{shell}_source"}, cwd=tmp_path)
    assert (ours.returncode, clicks.returncode) == (0, 0), ours.stderr + clicks.stderr
    assert ours.stdout == clicks.stdout
    assert "_ARMCTL_COMPLETE" in ours.stdout and f"{shell}_complete" in ours.stdout  # a real script, not ""
    as_module = subprocess.run([sys.executable, "-m", "armctl", "completion", shell], capture_output=True,
                               text=True, cwd=tmp_path, timeout=60)
    assert as_module.returncode == 0 and as_module.stdout == clicks.stdout  # for `armctl`, whatever ran it


@pytest.mark.parametrize("shell", SHELLS)
def test_in_process_the_output_is_clicks_source(shell):
    result = CliRunner().invoke(main, ["completion", shell])
    assert result.exit_code == 0, result.output
    expected = get_completion_class(shell)(main, {}, "armctl", "_ARMCTL_COMPLETE").source()
    assert result.output == expected


@pytest.mark.parametrize("shell", ["tcsh", "pwsh", "BASH", ""])
def test_an_unknown_shell_is_a_usage_error(shell, tmp_path):
    done = installed("completion", shell, cwd=tmp_path)
    assert done.returncode == 2
    assert done.stdout == ""
    assert "'bash', 'zsh', 'fish', 'powershell'" in done.stderr and "Traceback" not in done.stderr
    assert CliRunner().invoke(main, ["completion", shell]).exit_code == 2


def test_no_shell_is_a_usage_error(tmp_path):
    done = installed("completion", cwd=tmp_path)
    assert done.returncode == 2 and "Missing argument" in done.stderr


def test_the_installed_command_completes_its_own_commands(tmp_path):
    """What the shell asks once the script is loaded: the commands registered at import,
    including ``completion`` itself, and its shells."""
    words = installed(env={"_ARMCTL_COMPLETE": "bash_complete", "COMP_WORDS": "armctl com", "COMP_CWORD": "1"},
                      cwd=tmp_path)
    assert words.returncode == 0, words.stderr
    assert words.stdout.split() == ["plain,compile", "plain,completion"]
    shells = installed(env={"_ARMCTL_COMPLETE": "bash_complete", "COMP_WORDS": "armctl completion ",
                            "COMP_CWORD": "2"}, cwd=tmp_path)
    assert shells.stdout.split() == [f"plain,{shell}" for shell in SHELLS]


@pytest.mark.skipif(shutil.which("bash") is None, reason="no bash on this machine")
def test_bash_loads_the_script_and_completes_armctl(tmp_path):
    """As a person would: `eval "$(armctl completion bash)"`, then the completion function
    bash calls on Tab."""
    script = (
        'eval "$(armctl completion bash)"\n'
        "complete -p armctl\n"
        "COMP_WORDS=(armctl lint --for); COMP_CWORD=2; COMPREPLY=()\n"
        "_armctl_completion armctl\n"
        'echo "reply: ${COMPREPLY[*]}"\n'
    )
    env = {k: v for k, v in os.environ.items() if not k.endswith("_COMPLETE")}
    env["PATH"] = f"{INSTALLED.parent}{os.pathsep}{env.get('PATH', '')}"
    done = subprocess.run(["bash", "--norc", "--noprofile", "-c", script], capture_output=True, text=True,
                          cwd=tmp_path, env=env, timeout=60)
    assert done.returncode == 0, done.stderr
    assert "complete -o nosort -F _armctl_completion armctl" in done.stdout
    assert done.stdout.splitlines()[-1] == "reply: --format"
