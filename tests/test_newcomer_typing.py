"""Issue 26 item 8: a user's typed program — ``from armctl import Arm, ArmTimeout, RunResult`` —
passes ``mypy --strict`` (run when mypy is installed: the test extra has it), ``__all__`` is a
literal list type checkers can read, and ``record`` classes are dataclasses to them."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

import armctl

ROOT = Path(__file__).resolve().parents[1]
USER_PROGRAM = '''
from armctl import Arm, ArmTimeout, JobFailed, RunResult, ScriptError
def lift(port: str) -> RunResult | None:
    with Arm.open(port) as arm:
        result = arm.move(z=200)
        try:
            arm.move(x=300, timeout=0.5)
        except ArmTimeout as error:
            print(error.result)
        except (JobFailed, ScriptError) as error:
            print(error)
        return result


print(lift("sim://?clock=virtual"))
'''
RECORD_PROGRAM = '''
from armctl.script.source import Diagnostic, SourceSpan

span = SourceSpan("job.txt", 1, 1, 3, "G1 X5")
diagnostic: Diagnostic = Diagnostic.of("E001", span, "bad")
line: int = span.line
span.line = 2
'''


def test_all_is_a_literal_list_of_the_lazy_names():
    tree = ast.parse(Path(armctl.__file__).read_text(encoding="utf-8"))
    assigned = [node.value for node in ast.walk(tree) if isinstance(node, ast.Assign)
                and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets)]
    assert len(assigned) == 1 and isinstance(assigned[0], ast.List)
    assert armctl.__all__ == sorted(armctl._API)
    for name in armctl.__all__:
        assert getattr(armctl, name) is not None


def _mypy(tmp_path: Path, sources: dict[str, str], *, path_root: bool) -> subprocess.CompletedProcess:
    """``mypy --strict`` of the programs ``sources`` (file name -> text), in one run."""
    pytest.importorskip("mypy", reason="mypy is not installed (it is in the test extra: pip install -e '.[test]')")
    for name, source in sources.items():
        (tmp_path / name).write_text(source)
    env = {k: v for k, v in os.environ.items() if k != "MYPYPATH"}
    options = []
    if path_root:  # armctl from this checkout, however it was installed, checked as an installed package is:
        env["MYPYPATH"] = str(ROOT)  # its own findings are not the user's
        options = ["--follow-imports", "silent"]
    return subprocess.run([sys.executable, "-m", "mypy", "--strict", *options, "--cache-dir", str(tmp_path / "cache"),
                           *sources], capture_output=True, text=True, timeout=170, cwd=tmp_path, env=env)


@pytest.fixture(scope="module")
def checked(tmp_path_factory) -> tuple[dict[str, list[str]], subprocess.CompletedProcess]:
    """The user's program and the record program checked by one mypy run (a run costs seconds of
    CPU, mostly the standard library's stubs, the same for both): each file's error lines."""
    done = _mypy(tmp_path_factory.mktemp("mypy"), {"user.py": USER_PROGRAM, "records.py": RECORD_PROGRAM}, path_root=True)
    errors: dict[str, list[str]] = {"user.py": [], "records.py": []}
    for line in done.stdout.splitlines():
        if ": error:" in line:
            errors.setdefault(line.split(":", 1)[0], []).append(line)
    return errors, done


@pytest.mark.timeout(180)
def test_a_users_typed_program_passes_mypy_strict(checked):
    errors, done = checked
    assert "checked 2 source files" in done.stdout, done.stdout + done.stderr
    assert errors["user.py"] == [], done.stdout + done.stderr
    assert set(errors) == {"user.py", "records.py"}, done.stdout  # no error in another file either


@pytest.mark.timeout(180)
def test_record_classes_are_dataclasses_to_mypy(checked):
    errors, done = checked
    found = errors["records.py"]
    assert len(found) == 1 and "records.py:7:" in found[0] and "read-only" in found[0], done.stdout  # frozen: only the assignment


def _installed_through_an_import_hook() -> bool:
    """setuptools' default editable install: a finder on sys.meta_path that type checkers cannot follow."""
    return any("__editable__" in (getattr(finder, "__module__", "") or "") for finder in sys.meta_path)


@pytest.mark.timeout(180)
def test_the_installed_armctl_is_found_by_mypy(tmp_path):
    if _installed_through_an_import_hook():
        pytest.skip("armctl was installed with the default editable mode (an import hook mypy cannot follow): "
                    "README 'Install' says to use --config-settings editable_mode=strict")
    done = _mypy(tmp_path, {"user.py": USER_PROGRAM}, path_root=False)
    assert done.returncode == 0, done.stdout + done.stderr
