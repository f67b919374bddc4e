"""The pre-commit hook: .pre-commit-hooks.yaml says what pre-commit needs, and try-repo runs it.

The try-repo test builds pre-commit's own environment for this repository (a pip install from
the package index, a minute or more), so it is opt-in: it runs when pre-commit is installed and
ARMCTL_TEST_PRECOMMIT=1.  pre-commit installs the *committed* state of the repository (plus
changes to tracked files), so run it after armctl/lint/ and the hook file are committed.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HOOKS = ROOT / ".pre-commit-hooks.yaml"


def test_hook_file_declares_armctl_lint():
    text = HOOKS.read_text(encoding="utf-8")
    assert re.search(r"^- id: armctl-lint$", text, re.M)
    assert re.search(r"^  entry: armctl lint$", text, re.M)
    assert re.search(r"^  language: python$", text, re.M)
    files = re.search(r"^  files: '([^']+)'$", text, re.M).group(1)
    for name in ("job.txt", "a/b.arm", "x.gcode", "y.nc", "LOUD.GCODE"):
        assert re.search(files, name)
    for name in ("job.py", "notes.md", "txt"):
        assert not re.search(files, name)


def _pre_commit() -> str | None:
    beside = Path(sys.executable).with_name("pre-commit")
    return str(beside) if beside.exists() else shutil.which("pre-commit")


@pytest.mark.skipif(_pre_commit() is None, reason="pre-commit is not installed")
@pytest.mark.skipif(os.environ.get("ARMCTL_TEST_PRECOMMIT") != "1", reason="set ARMCTL_TEST_PRECOMMIT=1 (slow, uses the network)")
@pytest.mark.timeout(960)  # pre-commit's own install, bounded by the 900 s subprocess timeout
def test_try_repo_runs_the_hook(tmp_path):
    repo = tmp_path / "user-repo"
    (repo / "jobs").mkdir(parents=True)
    shutil.copy(ROOT / "scripts" / "pick_and_place.txt", repo / "jobs")
    # an error on any profile (L101; X500 would be a warning on the built-in profile's illustrative workspace)
    (repo / "jobs" / "bad.gcode").write_text("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\nG300 X260 Y10 Z150 R10\n"
                                             "G301 X250 Y0 Z150\n")
    env = dict(os.environ, PRE_COMMIT_HOME=str(tmp_path / "cache"))
    git = ["git", "-c", "user.email=test@example.com", "-c", "user.name=test"]
    subprocess.run([*git, "init", "-q"], cwd=repo, check=True)
    subprocess.run([*git, "add", "-A"], cwd=repo, check=True)

    def try_repo():
        return subprocess.run([_pre_commit(), "try-repo", str(ROOT), "armctl-lint", "--all-files"], cwd=repo,
                              env=env, capture_output=True, text=True, timeout=900)

    failed = try_repo()
    assert failed.returncode == 1, failed.stdout + failed.stderr
    assert "jobs/bad.gcode:3:1: L101" in failed.stdout
    subprocess.run([*git, "rm", "-q", "-f", "jobs/bad.gcode"], cwd=repo, check=True)
    passed = try_repo()
    assert passed.returncode == 0, passed.stdout + passed.stderr
    assert re.search(r"armctl lint.*Passed", passed.stdout)
