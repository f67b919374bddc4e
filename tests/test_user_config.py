"""The user-level armctl.toml and ``armctl config``.

Every test runs in an empty working directory (``project``: no armctl.toml above it) with
``XDG_CONFIG_HOME`` pointed at a temporary directory (``user``) and ``ARMCTL_PORT`` cleared,
so neither the developer's own files nor the environment change what is seen.  The layering is
tested on ``load_config``/``resolve_port`` values, through ``armctl config`` in-process
(CliRunner) and through the installed command in a fresh process.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.errors import ConfigError, ProfileError
from armctl.host.link import PortChoice, resolve_port
from armctl.host.profile import CONNECTOR_KEYS, find_config, load_config, load_profile, user_config_path


@pytest.fixture
def user(tmp_path, monkeypatch) -> Path:
    """The user's config directory's armctl folder (XDG_CONFIG_HOME/armctl), created empty."""
    home = tmp_path / "xdg"
    (home / "armctl").mkdir(parents=True)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(home))
    return home / "armctl"


@pytest.fixture
def project(tmp_path, monkeypatch) -> Path:
    directory = tmp_path / "project"
    directory.mkdir()
    monkeypatch.chdir(directory)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    assert find_config(directory)[0] is None, "an armctl.toml above the temporary directory"
    return directory


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def config_json(*args, env=None) -> dict:
    result = CliRunner().invoke(main, ["config", "--json", *args], env=env)
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


# --- where the file is and how it layers --------------------------------------------------------


def test_the_user_file_is_under_xdg_config_home(user, project):
    assert user_config_path() == user / "armctl.toml"


@pytest.mark.parametrize("value", [None, "", "   ", "/tmp/armctl-xdg", "relative/dir", "~/xdg"])
def test_the_user_file_is_where_platformdirs_puts_it(monkeypatch, value):
    """On Linux armctl spells platformdirs' rule itself (importing it costs 6 ms at every
    start); the two must agree."""
    platformdirs = pytest.importorskip("platformdirs")
    if value is None:
        monkeypatch.delenv("XDG_CONFIG_HOME", raising=False)
    else:
        monkeypatch.setenv("XDG_CONFIG_HOME", value)
    assert user_config_path() == Path(platformdirs.user_config_dir("armctl", appauthor=False)) / "armctl.toml"


def test_user_file_alone_gives_every_setting(user, project):
    path = write(user / "armctl.toml", 'port = "/dev/ttyACM0"\nbaud = 115200\n[lint]\nignore = ["L203"]\n')
    config = load_config()
    assert config.values == {"port": "/dev/ttyACM0", "baud": 115200, "lint": {"ignore": ["L203"]}}
    assert config.project_path is None and {config.path_of(k) for k in config.values} == {path}
    assert resolve_port(None, environ={}, config=config.values, config_path=config.path_of("port")) == \
        PortChoice("/dev/ttyACM0", str(path))


def test_project_file_wins_key_by_key_at_the_top_level(user, project):
    user_path = write(user / "armctl.toml", 'port = "/dev/ttyACM0"\nbaud = 115200\n[lint]\nignore = ["L203"]\nselect = ["E"]\n')
    project_path = write(project / "armctl.toml", 'baud = 57600\n[lint]\nignore = ["L101"]\n')
    config = load_config()
    assert config.values["port"] == "/dev/ttyACM0" and config.path_of("port") == user_path
    assert config.values["baud"] == 57600 and config.path_of("baud") == project_path.resolve()
    # a table comes whole from one file: the user's `select` does not leak into the project's [lint]
    assert config.values["lint"] == {"ignore": ["L101"]}


def test_environment_and_option_win_over_both_files(user, project):
    write(user / "armctl.toml", 'port = "/dev/ttyACM0"\n')
    assert config_json(env={"ARMCTL_PORT": "socket://127.0.0.1:7000"})["settings"]["port"] == \
        {"value": "socket://127.0.0.1:7000", "source": "environment", "where": "ARMCTL_PORT"}
    assert config_json("--port", "sim://", env={"ARMCTL_PORT": "socket://x:1"})["settings"]["port"] == \
        {"value": "sim://", "source": "option", "where": "--port"}


def test_profile_path_in_the_user_file_is_relative_to_it(user, project):
    write(user / "armctl.toml", 'profile = "arms/mine.toml"\n')
    write(user / "arms" / "mine.toml", 'name = "mine"\n[speed]\nattitude_deg_s = 33\n')
    assert load_profile().name == "mine"
    setting = config_json()["settings"]["profile"]
    assert setting == {"value": str(user / "arms" / "mine.toml"), "source": "user", "where": str(user / "armctl.toml")}


@pytest.mark.parametrize("text, message", [
    ("prot = 1\n", r"armctl\.toml: unknown key 'prot' \(did you mean 'port'\?\)"),
    ("baud = 12\n", r"armctl\.toml: baud = 12 must be a whole number"),
    ("port = \n", r"armctl\.toml:1:\d+: invalid TOML: "),
])
def test_user_file_errors_are_located_like_the_project_files(user, project, text, message):
    path = write(user / "armctl.toml", text)
    with pytest.raises((ConfigError, ProfileError), match=message) as caught:
        load_config()
    assert str(path) in str(caught.value)
    result = CliRunner().invoke(main, ["config"])
    assert result.exit_code == 2 and str(path) in result.stderr and result.stdout == ""


def test_a_sim_url_error_in_the_user_file_names_the_file(user, project):
    path = write(user / "armctl.toml", 'port = "sim://?bogus=1"\n')
    result = CliRunner().invoke(main, ["status", "--once"])
    assert result.exit_code == 2 and f"{path}: port" in result.stderr, result.output


# --- armctl config --------------------------------------------------------------------------------


def test_config_json_names_every_source(user, project):
    user_path = write(user / "armctl.toml", 'port = "sim://?clock=virtual"\n[jog]\n')
    project_path = write(project / "armctl.toml", '[lint]\nignore = ["L203"]\n').resolve()
    data = config_json()
    settings = data["settings"]
    connector = {f"connector.{key}" for key in CONNECTOR_KEYS}  # the arm's [connector], each with its source
    measured = {"timing.command_overhead_s"}  # measured by the probe too, from another section
    assert set(settings) == {"port", "baud", "profile", "lint", "jog"} | connector | measured
    assert settings["port"] == {"value": "sim://?clock=virtual", "source": "user", "where": str(user_path)}
    assert settings["lint"] == {"value": {"ignore": ["L203"]}, "source": "project", "where": str(project_path)}
    assert settings["baud"] == {"value": 9600, "source": "default", "where": None}
    assert settings["profile"]["source"] == "default"
    assert data["files"] == {"project": str(project_path), "user": str(user_path), "user_exists": True}


def test_config_text_says_where_each_setting_came_from(user, project):
    write(user / "armctl.toml", "baud = 115200\n")
    result = CliRunner().invoke(main, ["config"])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0] == "port     sim://  (built-in default)"
    assert lines[1] == f"baud     115200  (user: {user / 'armctl.toml'})"
    assert f"user file:    {user / 'armctl.toml'}" in lines


def test_installed_command_reads_the_user_file(user, project):
    """A fresh process, as a user runs it: the user file sets the port of `status`."""
    path = write(user / "armctl.toml", 'port = "sim://?clock=virtual"\n')
    env = {**os.environ, "XDG_CONFIG_HOME": str(user.parent)}
    env.pop("ARMCTL_PORT", None)
    shown = subprocess.run([sys.executable, "-m", "armctl", "config", "--json"], capture_output=True, text=True,
                           timeout=60, env=env, cwd=project)
    assert shown.returncode == 0, shown.stderr
    assert json.loads(shown.stdout)["settings"]["port"]["where"] == str(path)
    status = subprocess.run([sys.executable, "-m", "armctl", "status", "--once", "--json"], capture_output=True,
                            text=True, timeout=60, env=env, cwd=project)
    assert status.returncode == 0, status.stderr
    assert "using the built-in simulator (sim://?clock=virtual)" in status.stderr
    json.loads(status.stdout)
