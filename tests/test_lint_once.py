"""A job is checked once: ``armctl run`` prints the findings before it opens the port and hands
the ``CheckedScript`` to ``Arm.run``, which takes it as it is — one lint pass in all (a large
script paid three), and no module-level cache: the check is a value passed down.  A check made
for another profile or another first line is made afresh."""

from __future__ import annotations

import copy

import pytest
from click.testing import CliRunner

import armctl.lint.engine as engine
from armctl import Arm
from armctl.ui.cli import main
from armctl.core.checked import check
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


def test_a_checked_script_is_taken_as_it_is_and_another_check_made_afresh(passes):
    with Arm.open("sim://?clock=virtual") as arm:
        checked = check(ScriptSnapshot("a.txt", JOB.encode()), arm.profile)
        assert passes[0] == 1
        assert arm.run(checked).finished
        assert passes[0] == 1  # taken as it is
        other = copy.copy(arm.profile)  # equal, but another object: identity is what a check is for
        assert other is not arm.profile
        assert arm.run(check(checked.snapshot, other)).finished  # another profile: the arm's check
        assert passes[0] == 3
        assert arm.run(checked, from_line=3).finished  # another first line
        assert passes[0] == 4


def test_no_module_holds_a_check():
    import armctl.host.jobflow as jobflow

    assert not hasattr(jobflow, "_last_lint") and not hasattr(jobflow, "lint_script")
