"""Lint judges a job's motion time as run and estimate do (E012, armctl/core/estimate.py
``motion_time_overrun``), in time that follows the text: a delay or an external-axis value that
would keep the arm busy for days, and a loop that adds up past the bound."""

from __future__ import annotations

import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.ui.cli import main
from armctl.script.source import MAX_JOB_MOTION_S

FIRST = "G1 X250 Y0 Z150 A180 B0 C0 S1500 F3000\n"


def lint(tmp_path, text):
    path = tmp_path / "job.txt"
    path.write_text(text)
    return CliRunner().invoke(main, ["lint", str(path)])


def estimate(tmp_path, text):
    path = tmp_path / "job.txt"
    path.write_text(text)
    return CliRunner().invoke(main, ["estimate", str(path)])


@pytest.mark.parametrize("line", [
    "G4 P300000000000000000000000000000000000000",  # 3e38 ms
    "G1 U300000000000000000000000000000000000000",  # 3e38 degrees of an external axis
    f"G4 P{int(MAX_JOB_MOTION_S * 1000) + 1000}",
])
def test_one_statement_longer_than_the_bound_is_e012_in_lint_and_estimate(tmp_path, line):
    text = FIRST + line + "\n"
    for result in (lint(tmp_path, text), estimate(tmp_path, text)):
        assert result.exit_code == 1, result.output
        assert "job.txt:2:1: E012" in result.output
        assert "Traceback" not in result.output


@settings(max_examples=25, deadline=None)
@given(passes=st.integers(1, 400_000), delay_ms=st.integers(0, 2_000))
def test_a_repeated_delay_is_judged_by_lint_as_by_estimate(tmp_path_factory, passes, delay_ms):
    """Lint runs two passes of this loop (the rest repeat them) yet counts every pass's time."""
    tmp_path = tmp_path_factory.mktemp("job")
    text = FIRST + f"O<a> repeat [{passes}]\nG4 P{delay_ms}\nO<a> endrepeat\n"
    linted, estimated = lint(tmp_path, text), estimate(tmp_path, text)
    assert (linted.exit_code, estimated.exit_code) in ((0, 0), (1, 1)), (linted.output, estimated.output)
    assert ("E012" in linted.output) == ("E012" in estimated.output) == (linted.exit_code == 1)
