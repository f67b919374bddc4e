"""The rule table is complete by construction: every code is selectable from a fresh process.

Issue 10: the table used to fill only when armctl/lint/rules.py was imported; the tests imported
it first and passed while `armctl lint --ignore L203` failed for users.  So the tests that matter
here run the installed command in a fresh process (``python -m armctl``, with a timeout), and
the codes they try are computed from the table, so a new code inherits them.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.lint import registry
from armctl.lint.command import lint

TIMEOUT_S = 30  # bounds a hang on a loaded machine; not a speed assertion
CLEAN = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\n"


def every_code_and_prefix() -> list[str]:
    """Every code and every proper prefix of one ("E", "E0", "E00", "L", "L1", "L10", …)."""
    found = set()
    for code in registry.RULES:
        found.update(code[:k] for k in range(1, len(code) + 1))
    return sorted(found)


def armctl(*args: str, cwd: Path, stdin: str | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "armctl", *args], cwd=cwd, input=stdin, capture_output=True,
                          text=True, timeout=TIMEOUT_S)


# --- the table itself -----------------------------------------------------------------------------


def test_every_check_code_has_a_check_and_every_check_a_code():
    from armctl.lint import rules  # noqa: F401 - attaches the checks

    declared = {code for code, rule in registry.LINT_RULES.items() if rule.fed_by == "check"}
    assert registry.checked_codes() == declared
    assert {rule.fed_by for rule in registry.LINT_RULES.values()} <= {"check", registry.SOURCE}


def test_a_check_for_an_undeclared_or_taken_code_is_refused():
    with pytest.raises(ValueError, match="not a code declared"):
        registry.check("L999", on=registry.END)
    with pytest.raises(ValueError, match="not a code declared"):
        registry.check("L401", on=registry.END)  # the scanner's code
    from armctl.lint import rules  # noqa: F401

    with pytest.raises(ValueError, match="already has a check"):
        registry.check("L101", on=registry.END)


def test_the_table_is_complete_in_a_fresh_process_without_rules_imported(tmp_path):
    probe = ("import sys, json; from armctl.lint.registry import RULES; "
             "print(json.dumps([list(RULES), 'armctl.lint.rules' in sys.modules]))")
    result = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, capture_output=True, text=True,
                            timeout=TIMEOUT_S)
    codes, rules_imported = json.loads(result.stdout)
    assert codes == list(registry.RULES) and not rules_imported
    assert any(code.startswith("L") for code in codes)


# --- through the installed command, in a fresh process -------------------------------------------


def test_list_rules_in_a_fresh_process_lists_every_code(tmp_path):
    result = armctl("lint", "--list-rules", "--format", "json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert [record["code"] for record in json.loads(result.stdout)] == list(registry.RULES)


@pytest.mark.parametrize("option", ["--select", "--ignore"])
def test_every_code_and_prefix_is_accepted_in_a_fresh_process(tmp_path, option):
    (tmp_path / "job.txt").write_text(CLEAN)
    # one process per option: Selection stops at the first unknown entry, so every entry was accepted
    result = armctl("lint", option, ",".join(every_code_and_prefix()), "job.txt", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "unknown rule code" not in result.stderr


def test_every_code_in_the_config_ignore_list_is_accepted_in_a_fresh_process(tmp_path):
    (tmp_path / "job.txt").write_text(CLEAN + "G1 F30\n")  # L203, a warning
    listed = ", ".join(f'"{code}"' for code in registry.RULES)
    (tmp_path / "armctl.toml").write_text(f"[lint]\nignore = [{listed}]\n")
    result = armctl("lint", "--strict", "job.txt", cwd=tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "All checks passed" in result.stdout


JOB = CLEAN + "G1 F30\nG1 X500\n"  # L203 on line 2, L103 on line 3 (warnings on the built-in profile)


def test_the_readme_config_ignore_works_in_a_fresh_process(tmp_path):
    (tmp_path / "job.txt").write_text(JOB)
    (tmp_path / "armctl.toml").write_text('[lint]\nignore = ["L203"]\n')  # the README's example
    result = armctl("lint", "--strict", "job.txt", cwd=tmp_path)
    assert result.returncode == 1 and "L103" in result.stdout and "L203" not in result.stdout


@pytest.mark.parametrize("option, codes, shown, hidden", [
    ("--select", "E,L1", "L103", "L203"),  # the example in lint --help
    ("--select", "L2", "L203", "L103"),  # the README's
    ("--ignore", "L103", "L203", "L103"),  # a pre-commit hook's args: [--ignore, L103]
])
def test_help_readme_and_hook_examples_work_in_a_fresh_process(tmp_path, option, codes, shown, hidden):
    (tmp_path / "job.txt").write_text(JOB)
    result = armctl("lint", option, codes, "job.txt", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert shown in result.stdout and hidden not in result.stdout


def test_an_unknown_code_is_still_a_usage_error_in_a_fresh_process(tmp_path):
    (tmp_path / "job.txt").write_text(CLEAN)
    result = armctl("lint", "--ignore", "L999", "job.txt", cwd=tmp_path)
    assert result.returncode == 2 and "unknown rule code or prefix 'L999'" in result.stderr


# --- in-process, every code on its own ----------------------------------------------------------


@pytest.mark.parametrize("code", every_code_and_prefix())
def test_each_code_and_prefix_alone_is_selectable_in_process(tmp_path, code):
    (tmp_path / "job.txt").write_text(CLEAN)
    for option in ("--select", "--ignore"):
        result = CliRunner().invoke(lint, [option, code, str(tmp_path / "job.txt")])
        assert result.exit_code == 0, result.output
