"""Packaging: the grammar loads from the editable install and from a wheel; ``armctl --help``
stays light; ``python -m armctl`` works.

The wheel is built from a copy of the checkout (so no ``build/`` or ``*.egg-info`` lands in the
shared work tree), installed with ``pip install --no-deps --target``, and used from a directory
outside the repository with ``PYTHONPATH`` pointing at it and the editable install's import
finder removed — so the grammar can only come from inside the wheel.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

from test_cli_compile import motion

ROOT = Path(__file__).resolve().parents[1]
PYTHON = sys.executable  # the virtualenv's interpreter (armctl installed editable, lark & co. present)
SMALL_SCRIPT = "#<z> = 150\nG1 X250 Y0 Z#<z> A180 B0 C0 S1000 F3000 ; via Lark (a parameter)\nG4 P250\n"
SMALL_FRAMES = [
    motion("1", 1, f1=250, f2=0, f3=150, f4=180, f7=1000, f11=3000).hex(),
    motion("6", 0, f1=250).hex(),
]

# Compiles stdin and says where armctl and its grammar came from.  argv[1] == "wheel": drop the
# editable install's finder first, so only sys.path (PYTHONPATH) can provide armctl.
PROBE = """
import importlib.util, json, sys
if sys.argv[1] == "wheel":
    sys.meta_path[:] = [f for f in sys.meta_path if "__editable__" not in getattr(f, "__module__", "")]
import armctl
spec = importlib.util.find_spec("armctl.grammars")  # before the parser is built (no fallback yet)
from armctl.script import compile_text
from armctl.script.grammar import parser
job = compile_text(sys.stdin.read(), "<probe>")
frames = [statement.command.encode().hex() for statement in job]
import armctl.grammars
print(json.dumps({
    "armctl": armctl.__file__,
    "grammars_spec": None if spec is None else spec.origin,
    "grammars": armctl.grammars.__file__,
    "errors": job.error_count,
    "frames": frames,
    "lark_parser": type(parser()).__name__,
    "checkout_on_path": [p for p in sys.path if p.rstrip("/") in ("%(root)s", "%(root)s/armctl", "%(root)s/grammars")],
}))
"""


def probe(mode: str, cwd: Path, env: dict | None = None) -> dict:
    done = subprocess.run(
        [PYTHON, "-c", PROBE % {"root": str(ROOT)}, mode], input=SMALL_SCRIPT, capture_output=True, text=True,
        cwd=cwd, env={**os.environ, **(env or {})}, timeout=60,
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


# --- the editable install (the one this virtualenv has) ----------------------------------------


def test_the_grammar_loads_from_the_editable_install(tmp_path):
    found = probe("editable", cwd=tmp_path)
    real = {key: str(Path(found[key]).resolve()) for key in ("armctl", "grammars_spec", "grammars") if found[key]}
    # resolved: editable_mode=strict (README, for type checkers) links the checkout's files
    assert real["armctl"] == str(ROOT / "armctl" / "__init__.py")
    assert real.get("grammars_spec") == str(ROOT / "grammars" / "__init__.py")  # mapped by the install, not patched in
    assert real["grammars"] == str(ROOT / "grammars" / "__init__.py")
    assert (found["errors"], found["frames"]) == (0, SMALL_FRAMES)


# --- a wheel --------------------------------------------------------------------------------------

_NOT_SOURCE = shutil.ignore_patterns(".git", ".venv", "build", "dist", "*.egg-info", "__pycache__", ".hypothesis",
                                     ".pytest_cache", "tests")


def pip(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([PYTHON, "-m", "pip", *args], capture_output=True, text=True, cwd=cwd, timeout=300)


DISTRIBUTION = "armctl-serial"  # the name on the package index; `armctl` there is someone else's library
WHEEL_PREFIX = DISTRIBUTION.replace("-", "_")  # a wheel's file name normalises the name (PEP 427)

# building and installing the wheel (three pip calls of up to 300 s each) happens in the first
# test that uses it: that test's limit covers them, not the suite's 60 s default
WHEEL_TIME_LIMIT = pytest.mark.timeout(960)


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """(the wheel file, the --target directory it is installed in, how it was built)."""
    base = tmp_path_factory.mktemp("wheel")
    source, dist, target = base / "source", base / "dist", base / "installed"
    shutil.copytree(ROOT, source, ignore=_NOT_SOURCE)
    built = pip("wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(dist), str(source), cwd=base)
    how = "without build isolation"
    if built.returncode != 0 and "bdist_wheel" in built.stdout + built.stderr:
        # This virtualenv's setuptools cannot build wheels (see the xfail below): let pip fetch
        # a build backend into an isolated environment instead, to still test the wheel itself.
        built = pip("wheel", "--no-deps", "-q", "-w", str(dist), str(source), cwd=base)
        how = "with build isolation"
    assert built.returncode == 0, built.stdout + built.stderr
    (wheel_file,) = dist.glob(f"{WHEEL_PREFIX}-*.whl")
    installed = pip("install", "--no-deps", "-q", "--target", str(target), str(wheel_file), cwd=base)
    assert installed.returncode == 0, installed.stdout + installed.stderr
    return wheel_file, target, how


@WHEEL_TIME_LIMIT
def test_the_wheel_ships_the_grammar_as_package_data(wheel):
    wheel_file, _, _ = wheel
    names = zipfile.ZipFile(wheel_file).namelist()
    assert "armctl/grammars/armctl.lark" in names
    assert "armctl/grammars/__init__.py" in names
    assert not any(name.startswith("grammars/") for name in names)  # only inside the package
    assert not any(name.startswith("tests/") for name in names)


@WHEEL_TIME_LIMIT
def test_the_wheel_ships_armctl_serve_and_its_page(wheel):
    """``armctl serve``'s package and the page it serves at / (package data), and the extra."""
    wheel_file, _, _ = wheel
    names = zipfile.ZipFile(wheel_file).namelist()
    assert {"armctl/server/__init__.py", "armctl/server/app.py", "armctl/server/page/index.html", "armctl/aio.py"} <= set(names)
    assert any(value.startswith("aiohttp") and "serve" in value for value in _metadata(wheel_file)[0]["Requires-Dist"])


def _metadata(wheel_file: Path) -> tuple[dict[str, list[str]], str]:
    """The wheel's METADATA headers (name -> every value) and its entry_points.txt."""
    from email.parser import HeaderParser

    with zipfile.ZipFile(wheel_file) as archive:
        (metadata_name,) = [n for n in archive.namelist() if n.endswith(".dist-info/METADATA")]
        (entry_points_name,) = [n for n in archive.namelist() if n.endswith(".dist-info/entry_points.txt")]
        message = HeaderParser().parsestr(archive.read(metadata_name).decode())
        entry_points = archive.read(entry_points_name).decode()
    headers: dict[str, list[str]] = {}
    for key, value in message.items():
        headers.setdefault(key, []).append(value)
    return headers, entry_points


@WHEEL_TIME_LIMIT
def test_the_wheel_is_armctl_serial_with_the_armctl_command_and_package(wheel):
    wheel_file, target, _ = wheel
    headers, entry_points = _metadata(wheel_file)
    assert headers["Name"] == [DISTRIBUTION]
    assert headers["Version"] == ["0.1.0"]
    assert "[console_scripts]\narmctl = armctl.ui.cli:main" in entry_points  # the command keeps its name
    assert headers.get("License-Expression") == ["MIT"]  # SPDX (PEP 639), not the deprecated table
    assert headers["Requires-Python"] == [">=3.11"]
    classifiers = headers["Classifier"]
    for version in ("3.11", "3.12", "3.13"):
        assert f"Programming Language :: Python :: {version}" in classifiers
    assert "Typing :: Typed" in classifiers
    assert not any(c.startswith("License ::") for c in classifiers)  # PEP 639: the expression says it
    assert "robot arm" in headers["Keywords"][0].split(",")
    names = zipfile.ZipFile(wheel_file).namelist()
    assert "armctl/py.typed" in names  # PEP 561: type checkers use the package's annotations
    assert (target / "armctl" / "py.typed").is_file()
    assert not any(name.split("/")[0] not in ("armctl",) and not name.startswith(f"{WHEEL_PREFIX}-")
                   for name in names)  # one import package, `armctl`, and the wheel's own .dist-info


def test_the_pyproject_names_no_invented_urls():
    """No [project.urls] until the project has a public home: a placeholder host would send
    users (and the index page) somewhere that is not this project."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["name"] == DISTRIBUTION
    assert project["scripts"] == {"armctl": "armctl.ui.cli:main"}
    for url in project.get("urls", {}).values():
        assert "<" not in url and "example" not in url, url


@WHEEL_TIME_LIMIT
def test_the_grammar_loads_from_the_wheel_outside_the_repository(wheel, tmp_path):
    _, target, _ = wheel
    found = probe("wheel", cwd=tmp_path, env={"PYTHONPATH": str(target)})
    assert found["checkout_on_path"] == []
    assert found["armctl"] == str(target / "armctl" / "__init__.py")
    assert found["grammars_spec"] == str(target / "armctl" / "grammars" / "__init__.py")
    assert found["grammars"] == str(target / "armctl" / "grammars" / "__init__.py")
    assert (found["errors"], found["frames"]) == (0, SMALL_FRAMES)


@WHEEL_TIME_LIMIT
def test_the_wheels_command_line_compiles_outside_the_repository(wheel, tmp_path):
    _, target, _ = wheel
    script = tmp_path / "job.txt"
    script.write_text(SMALL_SCRIPT)
    code = ("import sys; sys.meta_path[:] = [f for f in sys.meta_path if '__editable__' not in "
            "getattr(f, '__module__', '')]; from armctl.ui.cli import main; main()")
    done = subprocess.run([PYTHON, "-c", code, "compile", "job.txt"], capture_output=True, text=True, cwd=tmp_path,
                          env={**os.environ, "PYTHONPATH": str(target)}, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == SMALL_FRAMES


def test_the_test_extra_provides_what_a_wheel_build_without_isolation_needs():
    extra = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]["test"]
    names = {requirement.split("[")[0].split(">")[0].split("=")[0].split("<")[0].strip().lower() for requirement in extra}
    assert "wheel" in names or any(r.replace(" ", "").lower().startswith("setuptools>=7") for r in extra)


# --- the command line stays light and answers as a module -----------------------------------------

HEAVY = ("lark", "rich", "serial")


def test_help_does_not_import_lark_rich_or_serial(tmp_path):
    code = (
        "import sys\n"
        "from armctl.ui.cli import main\n"
        "main(['--help'], standalone_mode=False)\n"
        f"heavy = sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r})\n"
        "print('HEAVY', heavy)\n"
    )
    done = subprocess.run([PYTHON, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=60)
    assert done.returncode == 0, done.stderr
    assert "Usage: " in done.stdout and "compile" in done.stdout and "run" in done.stdout
    heavy_line = done.stdout.splitlines()[-1]
    assert heavy_line == "HEAVY []"


def test_python_dash_m_armctl_version(tmp_path):
    done = subprocess.run([PYTHON, "-m", "armctl", "--version"], capture_output=True, text=True, cwd=tmp_path, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "armctl, version 0.1.0\n"


def test_python_dash_m_armctl_help_lists_the_commands(tmp_path):
    done = subprocess.run([PYTHON, "-m", "armctl", "--help"], capture_output=True, text=True, cwd=tmp_path, timeout=60)
    assert done.returncode == 0
    for command in ("compile", "completion", "decode", "estimate", "ports", "run", "sim", "status"):
        assert f"  {command} " in done.stdout, command
