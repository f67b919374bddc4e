"""Issue 26 item 9: a LICENSE file as pyproject says, the grammar cache in platformdirs' user
cache folder, and PowerShell completion (click 8.5's, through ``armctl completion powershell``)."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from armctl.host import folders
from armctl.host.folders import user_folder

ROOT = Path(__file__).resolve().parents[1]
ARMCTL = Path(sys.executable).with_name("armctl")


def test_the_license_file_is_mit_and_named_by_pyproject():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == "MIT" and project["license-files"] == ["LICENSE"]
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License") and "Permission is hereby granted, free of charge" in text


@pytest.mark.parametrize("kind, variable", [("cache", "XDG_CACHE_HOME"), ("config", "XDG_CONFIG_HOME")])
@pytest.mark.parametrize("value", ["/somewhere/absolute", "", "relative/ignored", None])
def test_on_linux_the_folders_are_platformdirs_own(monkeypatch, kind, variable, value):
    platformdirs = pytest.importorskip("platformdirs")
    monkeypatch.setattr(sys, "platform", "linux")
    if value is None:
        monkeypatch.delenv(variable, raising=False)
    else:
        monkeypatch.setenv(variable, value)
    expected = (platformdirs.user_cache_dir if kind == "cache" else platformdirs.user_config_dir)("armctl", appauthor=False)
    assert user_folder(kind) == Path(expected)


@pytest.mark.parametrize("platform", ["darwin", "win32"])
def test_elsewhere_platformdirs_decides(monkeypatch, platform):
    import platformdirs

    monkeypatch.setattr(sys, "platform", platform)
    monkeypatch.setattr(platformdirs, "user_cache_dir", lambda name, appauthor: f"/os/{name}/Cache/{appauthor}")
    assert user_folder("cache") == Path("/os/armctl/Cache/False")
    assert folders.APP_NAME == "armctl"


def test_the_grammar_cache_lives_in_the_user_cache_folder(monkeypatch, tmp_path):
    from armctl.script.grammar import cache_path

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    assert Path(cache_path()).parent == tmp_path / "cache" / "armctl" == user_folder("cache")


def _armctl(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([str(ARMCTL), *args], capture_output=True, text=True, timeout=50,
                          env={**os.environ, **(env or {})})


@pytest.mark.timeout(60)
def test_powershell_completion_script_and_answers():
    script = _armctl("completion", "powershell")
    assert script.returncode == 0, script.stderr
    assert "Register-ArgumentCompleter" in script.stdout and "_ARMCTL_COMPLETE" in script.stdout
    answer = _armctl(env={"_ARMCTL_COMPLETE": "powershell_complete", "COMP_WORDS": "armctl ru", "COMP_CWORD": "1"})
    assert answer.returncode == 0, answer.stderr
    assert "run" in answer.stdout.splitlines()
    options = _armctl(env={"_ARMCTL_COMPLETE": "powershell_complete", "COMP_WORDS": "armctl run job.txt --ab",
                           "COMP_CWORD": "3"})
    assert "--abort" in options.stdout.splitlines()
