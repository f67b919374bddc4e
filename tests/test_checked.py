"""A checked job is a value (armctl/core/checked.py): checked once before any port opens, planned once
from the arm's report, and what streams is what was estimated, frame for frame."""

from __future__ import annotations

import dataclasses

import pytest

from armctl import Arm, ScriptError
from armctl.core.checked import CheckedScript, check, checked_for, plan, start_at
from armctl.core.motion import MotionModel
from armctl.host.profile import load_profile
from armctl.script.files import ScriptSnapshot

pytestmark = pytest.mark.timeout(60)
JOB = ("G90\nG1 X250 Y0 Z150 A180 B0 C0 F3000 S1000\nO<a> repeat [3]\nG1 Y10\nG1 Y0\nO<a> endrepeat\n"
       "G300 X255 Y5 R5 F900\nG301 X250 Y10\nG1 Y0 F3000\n")


def snapshot(text: str = JOB) -> ScriptSnapshot:
    return ScriptSnapshot("job.txt", text.encode())


def test_a_checked_script_is_frozen_and_knows_why_it_is_refused():
    checked = check(snapshot(), load_profile())
    assert isinstance(checked, CheckedScript) and checked.refusal() is None and checked.errors == 0
    with pytest.raises(dataclasses.FrozenInstanceError):
        checked.from_line = 2  # type: ignore[misc]
    bad = check(snapshot("G1 X250 Y0 Z150 A180 B0 C0 F3000 S9000\n"), load_profile())  # S outside 500…2500
    assert isinstance(bad.refusal(), ScriptError) and bad.refusal().diagnostics[0].code == bad.diagnostics[0].code


def test_a_from_line_the_compiler_cannot_start_at_is_the_refusal():
    profile = load_profile()
    inside = check(snapshot(), profile, from_line=4)  # inside the repeat block
    assert inside.lint_error() is None and inside.refusal() is inside.from_line_error is not None
    assert check(snapshot(), profile).starting_at(4).refusal().diagnostics == inside.refusal().diagnostics
    assert check(snapshot(), profile, from_line=3).refusal() is None  # the block's opening line
    assert check(snapshot(), profile, from_line=8).refusal() is not None  # the arc's end


def test_the_same_check_is_taken_as_it_is_another_made_afresh():
    profile = load_profile()
    checked = check(snapshot(), profile)
    assert checked_for(checked, profile) is checked
    assert checked_for(checked, profile, from_line=3) is not checked
    assert checked_for(checked, dataclasses.replace(profile)) is not checked  # another profile object


def test_what_streams_is_what_was_estimated():
    profile = load_profile()
    model = MotionModel(profile)
    start, initial = start_at(model)
    job = plan(check(snapshot(), profile), model, start, initial, 2.0, 9600)
    statements = list(job.statements())
    assert len(statements) == job.estimate.frames == 1 + 3 * 2 + 2 + 1  # G1, 3 passes of 2, the arc's 2, G1
    again = [s.command.encode() for s in job.statements()]
    assert again == [s.command.encode() for s in statements]


def test_a_job_too_long_is_refused_by_the_plan_too():
    profile = load_profile()
    model = MotionModel(profile)
    start, initial = start_at(model)
    long_delay = check(snapshot("O<a> repeat [2000]\nG4 P60000\nO<a> endrepeat\n"), profile)  # 2,000 minutes
    assert long_delay.refusal().diagnostics[0].code == "E012"
    with pytest.raises(ScriptError, match="motion time passes"):
        plan(long_delay, model, start, initial, 2.0, 9600)


def test_arm_run_sends_nothing_for_a_refused_checked_script():
    with Arm.open("sim://?clock=virtual") as arm:
        refused = check(snapshot("G1 X250 Y0 Z150 A180 B0 C0 F3000 S9000\n"), arm.profile)
        with pytest.raises(ScriptError):
            arm.run(refused)
        assert arm.run(check(snapshot(), arm.profile)).finished
