"""A job is checked once: ``armctl run`` prints the findings before it opens the port and hands
the same snapshot to ``Arm.run``, which checks it when submitted and again on its worker — one
lint pass in all (a large script paid three).  The report is reused only for the very same
snapshot, profile and initial state."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

import armctl.lint.engine as engine
from armctl import Arm
from armctl.cli import main
from armctl.jobflow import lint_script
from armctl.profile import load_profile
from armctl.script.files import ScriptSnapshot

pytestmark = pytest.mark.timeout(60)
JOB = "G90\nG1 X250 Y0 Z150 A180 B0 C0 F3000 S1000\nG1 X240 Y10 Z150\n"


@pytest.fixture
def passes(monkeypatch):
    count = [0]
    original = engine.lint_lines

    def counting(*args, **kwargs):
        count[0] += 1
        return original(*args, **kwargs)

    monkeypatch.setattr(engine, "lint_lines", counting)
    return count


def test_armctl_run_lints_the_job_once(passes, tmp_path):
    script = tmp_path / "job.txt"
    script.write_text(JOB)
    result = CliRunner().invoke(main, ["run", str(script), "--no-live", "--port", "sim://?clock=virtual"],
                                env={"ARMCTL_PORT": None})
    assert result.exit_code == 0, result.output
    assert passes[0] == 1


def test_arm_run_lints_the_job_once(passes):
    with Arm.open("sim://?clock=virtual") as arm:
        assert arm.run(JOB).finished
    assert passes[0] == 1


def test_another_snapshot_or_profile_is_checked_afresh(passes):
    profile = load_profile()
    first = ScriptSnapshot("a.txt", JOB.encode())
    same_bytes = ScriptSnapshot("a.txt", JOB.encode())
    assert lint_script(first, profile) is lint_script(first, profile)
    assert passes[0] == 1
    lint_script(same_bytes, profile)  # equal but not the same object: no identity, no reuse
    lint_script(first, load_profile())
    assert passes[0] == 3
