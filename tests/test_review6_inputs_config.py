"""Review 6, hostile inputs: ``armctl config`` refuses what the command that reads it refuses.

Property (Hypothesis, in process, through click's CliRunner): for any port a user may write —
``sim://`` in any case, with any options and a profile file that is good, missing, a directory
or bad; a network URL; a scheme nothing handles; a device path — given as ``--port`` or as
``ARMCTL_PORT``:

- ``armctl config`` exits 0 or 2, never with a traceback;
- when ``armctl status --once`` (on a virtual clock, so nothing waits) exits 2 — a usage or
  configuration error — ``armctl config`` exits 2 too, and says why on stderr.

Only the ``sim://`` ports are opened (the simulator, in this process); the others are checked
against the resolution every port-opening command makes before it opens anything
(``choose_port`` and the arm's identity, ``calibration.with_arm``).
"""

from __future__ import annotations

import os

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from armctl.errors import ArmctlError
from armctl.ui.cli import main

SETTINGS = settings(max_examples=50, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])

PROFILES = {"good.toml": b"[connector]\nfifo_frames = 150\n", "bad.toml": b"[joints]\nj1_deg = [1.0, -1.0]\n",
            "latin1.toml": b"name = \"\xe9\"\n"}
PROFILE_VALUES = [*PROFILES, "missing.toml", "adir", "", "/dev/zero", "%00"]


def _option_names() -> list[str]:
    from armctl.sim.protocol_sim import OPTION_NAMES

    return list(OPTION_NAMES)


values = st.one_of(st.sampled_from(["1", "0", "-1", "50", "2.5", "nan", "inf", "1e9", "", "virtual", "wall", "queued",
                                    "arrival", "robot", "worktable", "x"]), st.text(max_size=4))
options = st.lists(st.one_of(
    st.tuples(st.sampled_from(_option_names()), values),
    st.tuples(st.just("profile"), st.sampled_from(PROFILE_VALUES)),
    st.tuples(st.text(max_size=5), values)), max_size=4)
sim_ports = st.tuples(st.sampled_from(["sim", "SIM", "Sim"]), options).map(
    lambda parts: f"{parts[0]}://?" + "&".join(f"{k}={v}" for k, v in [("clock", "virtual"), *parts[1]]))
other_ports = st.one_of(
    st.sampled_from(["socket://localhost:1", "socket://localhost", "socket://[::1", "socket://host:99999",
                     "rfc2217://localhost:1", "loop://", "http://arm", " sim://", "bogus://x", "/dev/ttyUSB9",
                     "COM3", "-", "sim://x", "sim://?clock=virtual#x", "/dev/tty\0", "://\0"]),
    st.tuples(st.text(max_size=6), st.text(max_size=10)).map(lambda parts: f"{parts[0]}://{parts[1]}"))


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for name in [k for k in os.environ if k.startswith("ARMCTL_")]:
        monkeypatch.delenv(name)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    for name, content in PROFILES.items():
        (tmp_path / name).write_bytes(content)
    (tmp_path / "adir").mkdir()
    return tmp_path


def _invoke(args, env=None):
    result = CliRunner().invoke(main, args, env=env, catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise AssertionError(f"armctl {' '.join(args)} raised {result.exception!r}") from result.exception
    assert "Traceback" not in result.stderr, result.stderr
    return result


def _config_agrees(port: str, refused: bool, how: str) -> None:
    ways = [(["config", "--port", port], None)]
    if "\0" not in port:  # (no environment variable can hold a NUL)
        ways.append((["config"], {"ARMCTL_PORT": port}))
    for args, env in ways:
        result = _invoke(args, env)
        assert result.exit_code in (0, 2), (port, result.exit_code, result.stderr)
        if refused:
            assert result.exit_code == 2 and result.stderr.strip(), f"{how} refuses {port!r}; config: {result.stdout}"


@pytest.mark.timeout(300)
@SETTINGS
@given(port=sim_ports)
def test_config_refuses_a_sim_port_that_status_refuses(workdir, port):
    status = _invoke(["status", "--once", "--timeout", "0.5", "--port", port])
    assert status.exit_code in (0, 1, 2), (port, status.exit_code, status.stderr)
    _config_agrees(port, status.exit_code == 2, f"status --once (exit 2: {status.stderr.strip()[-200:]})")


@pytest.mark.timeout(300)
@SETTINGS
@given(port=other_ports)
def test_config_refuses_a_port_the_commands_refuse_before_opening_it(workdir, port):
    from armctl.host.calibration import with_arm
    from armctl.host.link import choose_port

    try:
        with_arm(choose_port(port))
        refused = False
    except ArmctlError:
        refused = True
    _config_agrees(port, refused, "choose_port")


@pytest.mark.parametrize("port", ["/dev/ttyUSB0\0", "socket://\0:1", "sim://?clock=virtual\0", "loop://\0"])
def test_a_port_holding_a_nul_is_refused_by_the_api_and_config(workdir, port):
    """``Arm.open(port=…)`` can be given a NUL, a command line cannot (in process, ``--port`` can)."""
    from armctl import Arm
    from armctl.errors import ConfigError

    with pytest.raises(ConfigError, match="NUL"):
        Arm.open(port)
    result = _invoke(["config", "--port", port])
    assert result.exit_code == 2 and "NUL" in result.stderr, result.stderr
