"""A bad port is named as the caller gave it: ``--port`` on the command line, ``port`` to
``Arm.open``, ``--arm NAME`` to ``armctl serve`` (the API and serve said "--port", an option
neither has; found by a review), ``ARMCTL_PORT`` or the armctl.toml it came from."""

from __future__ import annotations

import subprocess
import sys

import pytest

from armctl import Arm, ConfigError
from armctl.host.port_choice import PortChoice, resolve_port

pytestmark = pytest.mark.timeout(60)


def test_arm_open_names_its_own_argument():
    with pytest.raises(ConfigError, match=r"^port: unknown option 'bogus' in 'sim://\?bogus=1'"):
        Arm.open("sim://?bogus=1")


def test_serve_names_the_arm_option_that_gave_the_port(tmp_path):
    served = subprocess.run([sys.executable, "-m", "armctl", "serve", "--arm", "left=sim://?bogus=1"],
                            capture_output=True, text=True, timeout=50, cwd=tmp_path)
    if "pip install" in served.stderr:
        pytest.skip("the serve extra (aiohttp) is not installed")
    assert served.returncode == 2, served.stderr
    assert "armctl: --arm left: unknown option 'bogus' in 'sim://?bogus=1'" in served.stderr
    assert "Traceback" not in served.stderr


def test_the_command_line_and_the_files_keep_their_names():
    assert resolve_port("sim://", environ={}) == PortChoice("sim://", "--port")
    assert resolve_port(None, environ={"ARMCTL_PORT": "/dev/ttyUSB0"}).origin == "ARMCTL_PORT"
    from_file = resolve_port(None, environ={}, config={"port": "sim://"}, config_path="/p/armctl.toml")
    assert from_file.origin == "/p/armctl.toml" and from_file.from_file
    assert not resolve_port("sim://", environ={}, origin="--arm a").from_file
    with pytest.raises(ConfigError, match=r"^port is empty: .* or leave port out$"):
        resolve_port(" ", environ={}, origin="port")
