"""Every number a user gives — an option, a ``sim://`` option, a profile or armctl.toml value —
is either accepted (and then the command ends, without a traceback) or refused with exit 2 and a
message naming it.  Issue 10: ``--lead nan`` removed the lead, ``--timeout nan`` waited for ever,
``max_joint_deg_s = 1e308`` divided by zero, ``port = []`` quietly chose the simulator.

The lists of options and keys come from click's command objects, the ``sim://`` parser's table
and the profile schema, so a new option or key inherits these tests.  In-process through
CliRunner, plus a few cases through a fresh ``python -m armctl`` (a registry that fills on
import would pass in-process and fail for users).
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import urllib.parse
from pathlib import Path

import click
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from armctl.ui.cli import main
from armctl.ui.cli_types import Bounded
from armctl.host.profile import PROFILE_SCHEMA, find_config

from cli_catalogue import numeric_options, quick_args

ARMCTL = [sys.executable, "-m", "armctl"]
FAST_SIM = "sim://?clock=virtual"
SCRIPT_TEXT = "G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 S1500 F30\nPOSE 1\nG4 P100\nPOSE 0\n"

# How to invoke each command so that a value its options accept ends quickly: a virtual clock,
# a script, or a usage error that comes after option parsing (sim: --pty with --tcp; jog: stdin
# is not a terminal).  A new command must be added here: the test below says so.

SPECIAL_NUMBERS = [
    "nan", "-nan", "NaN", "inf", "-inf", "+inf", "Infinity", "1e308", "-1e308", "1e309", "-1e309",
    "3.4028235e38", "3.4028234e38", "3.4028236e38", "-3.4028235e38", "340282346638528859811704183484516925440",
    "0", "-0", "-1", "1e-308", "5e-324", "0.0001", "99999999999999999999999", str(2**63), str(-(2**63)),
    "abc", "", " ", "1,5", "0x10", "1e5", "١", "٢.٥", "１０",
]
VALUE_TEXTS = st.one_of(
    st.sampled_from(SPECIAL_NUMBERS),
    st.integers(min_value=-(10**30), max_value=10**30).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.floats(min_value=-1e6, max_value=1e6).map(lambda v: f"{v:g}"),
)


NUMERIC_OPTIONS = [(path[0], param) for path, param in numeric_options()]


def _accepts(param: click.Option, text: str) -> bool:
    """The oracle: a finite number inside the declared bounds (a whole one for integer options)."""
    kind = param.type
    if not text.isascii():  # "١" is a number to int() and float(), not to armctl
        return False
    try:
        value = int(text) if isinstance(kind, click.IntRange) else float(text)
    except ValueError:
        return False
    return math.isfinite(value) and kind.min <= value <= kind.max


@pytest.fixture(autouse=True)
def _clean_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    assert find_config(tmp_path)[0] is None, "an armctl.toml above the temporary directory would change these tests"


@pytest.fixture
def script(tmp_path) -> Path:
    path = tmp_path / "job.txt"
    path.write_text(SCRIPT_TEXT)
    return path


def _invoke(args, **kwargs):
    return CliRunner().invoke(main, [str(a) for a in args], **kwargs)


def _no_traceback(result):
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert "Traceback" not in result.output


# --- command-line options -----------------------------------------------------------------------


def test_the_option_list_is_read_from_click_and_is_not_empty():
    names = {(command, param.opts[-1]) for command, param in NUMERIC_OPTIONS}
    assert {("run", "--lead"), ("run", "--timeout"), ("status", "--timeout"), ("estimate", "--baud"),
            ("jog", "--repeat-delay"), ("sim", "--tcp"), ("run", "--from-line")} <= names


@pytest.mark.parametrize("command, param", NUMERIC_OPTIONS, ids=lambda p: getattr(p, "name", p))
def test_every_numeric_option_is_bounded_on_both_sides(command, param):
    assert isinstance(param.type, Bounded), f"{command} {param.opts[-1]}: declare it with armctl.ui.cli_types.number()"
    assert math.isfinite(param.type.min) and math.isfinite(param.type.max)


@pytest.mark.parametrize("command, param", NUMERIC_OPTIONS, ids=lambda p: getattr(p, "name", p))
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=VALUE_TEXTS)
def test_a_numeric_option_accepts_its_range_and_refuses_everything_else_with_exit_2(command, param, text, script):
    option = param.opts[-1]
    args = [*quick_args((command,), script), f"{option}={text}"]
    result = _invoke(args)
    _no_traceback(result)
    refused = f"Invalid value for '{option}'" in result.output
    if _accepts(param, text):
        assert not refused, result.output
    else:
        assert refused and result.exit_code == 2, result.output


@pytest.mark.parametrize("args", [
    ["run", "{script}", "--dry-run", "--lead", "nan"],
    ["status", "--port", FAST_SIM, "--timeout", "nan"],
    ["estimate", "{script}", "--lead", "-inf"],
    ["run", "{script}", "--from-line", "99999999999999999999"],
])
def test_nan_and_out_of_range_options_exit_2_through_the_installed_command(args, script, tmp_path):
    option = next(a for a in args if a.startswith("--") and a not in ("--dry-run", "--port"))
    done = subprocess.run([*ARMCTL, *(a.format(script=script) for a in args)], capture_output=True, text=True,
                          timeout=60, cwd=tmp_path, env={k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"})
    assert done.returncode == 2, done.stderr
    assert f"'{option}'" in done.stderr and "Traceback" not in done.stderr


# --- sim:// options ------------------------------------------------------------------------------


def _sim_options():
    from armctl.sim.protocol_sim import OPTION_NAMES

    return [name for name in OPTION_NAMES
            if name not in ("clock", "control", "control_frames", "status_xyz_frame", "profile")]


WHOLE_NUMBER_OPTIONS = ("baud", "fifo", "fifo_frames", "seed", "write_buffer_bytes")  # read with int(): blanks stripped


def _sim_accepts(name: str, text: str) -> bool:
    from armctl.core import limits
    ranges = {"speed": limits.SIM_TIME_SCALE_RANGE, "slowdown": limits.SIM_SLOWDOWN_RANGE, "baud": limits.BAUD_RANGE,
              "fifo": limits.SIM_FIFO_RANGE_FRAMES, "seed": limits.SIM_SEED_RANGE, "loss": limits.SIM_RATE_RANGE,
              "corrupt": limits.SIM_RATE_RANGE, "noise": limits.SIM_RATE_RANGE,
              "speed_factor": limits.SIM_SLOWDOWN_RANGE, "fifo_frames": limits.SIM_FIFO_RANGE_FRAMES,
              "link_scale": limits.SIM_LINK_SCALE_RANGE, "write_buffer_bytes": limits.SIM_WRITE_BUFFER_RANGE_BYTES,
              "read_granularity_ms": limits.SIM_READ_GRANULARITY_RANGE_MS,
              "status_jitter_ms": limits.STATUS_JITTER_RANGE_MS}
    low, high = ranges[name]
    if not text.isascii():  # "١" is a number to int() and float(), not in a URL
        return False
    try:
        value = int(text) if isinstance(low, int) else float(text)
    except ValueError:
        return False
    return math.isfinite(value) and low <= value <= high


def test_every_numeric_sim_option_has_an_oracle_here():
    for name in _sim_options():
        _sim_accepts(name, "1")


@pytest.mark.parametrize("name", _sim_options())
@settings(max_examples=30, deadline=None)
@given(text=VALUE_TEXTS)
def test_a_sim_option_is_parsed_or_refused_naming_it(name, text):
    from armctl.sim.protocol_sim import SimOptionError, parse_sim_url

    url = f"sim://?{name}={urllib.parse.quote(text)}"
    if _sim_accepts(name, text.strip() if name in WHOLE_NUMBER_OPTIONS else text):
        parse_sim_url(url)
    else:
        with pytest.raises(SimOptionError, match=rf"^{name} must be"):
            parse_sim_url(url)


# speed and read_granularity_ms: no virtual clock (each refused with it, whatever its value: its own test)
@pytest.mark.parametrize("name", [n for n in _sim_options() if n not in ("speed", "read_granularity_ms")])
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=st.sampled_from(SPECIAL_NUMBERS))
def test_every_port_command_refuses_a_bad_sim_option_with_exit_2(name, text, script):
    url = f"{FAST_SIM}&{name}={urllib.parse.quote(text)}"
    result = _invoke(["status", "--once", "--port", url, "--timeout", "0.5"])
    _no_traceback(result)
    accepted = _sim_accepts(name, text.strip() if name in WHOLE_NUMBER_OPTIONS else text)
    if accepted:
        assert result.exit_code in (0, 1), result.output
    else:
        assert result.exit_code == 2 and f"--port: {name} must be" in result.output, result.output
        run = _invoke(["run", script, "--no-live", "--port", url])
        assert run.exit_code == 2 and f"--port: {name} must be" in run.output, run.output


@pytest.mark.parametrize("url, message", [
    ("sim://?sped=4", "did you mean 'speed'"),
    ("sim://?fifo=99999999999999999999", "fifo must be a whole number 1…100000"),
    ("sim://?profile=/no/such/profile.toml", "file not found"),
    ("sim://elsewhere", "takes its options after '?'"),
])
def test_bad_sim_urls_exit_2_on_run_status_and_sim(url, message, script, tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    for args in (["status", "--once", "--port", url], ["run", str(script), "--no-live", "--port", url],
                 ["sim", "--tcp", "1", "--url", url]):
        done = subprocess.run([*ARMCTL, *args], capture_output=True, text=True, timeout=60, cwd=tmp_path, env=env)
        assert done.returncode == 2, (args, done.stderr)
        assert message in done.stderr and "Traceback" not in done.stderr


def test_a_bad_sim_option_from_armctl_port_says_where_it_came_from():
    result = _invoke(["status", "--once"], env={"ARMCTL_PORT": "sim://?loss=2"})
    assert result.exit_code == 2 and "ARMCTL_PORT: loss must be a number 0…1" in result.output, result.output


# --- which port ------------------------------------------------------------------------------------


@pytest.mark.parametrize("toml, message", [
    ('prot = "/dev/ttyUSB0"\n', "unknown key 'prot' (did you mean 'port'?)"),
    ("port = []\n", "port = [] must be a device path or URL"),
    ('port = ""\n', "port = '' must be a device path or URL"),
    ("port = 3\n", "port = 3 must be a device path or URL"),
    ("baud = nan\n", "baud = nan must be a whole number of bit/s"),
    ("baud = 1e308\n", "baud = 1e+308 must be a whole number of bit/s"),
    ('port = "sim://?slowdown=inf"\n', "armctl.toml: port: slowdown must be a number 0.1…10, not 'inf'"),
    ("[lnt]\n", "unknown key 'lnt' (did you mean 'lint'?)"),
    ("jog = 1\n", "jog = 1 must be a table"),
    ('profile = ""\n', "profile = '' must be a table ([profile]) or a path string"),
])
def test_armctl_toml_mistakes_are_located_config_errors_never_the_simulator(tmp_path, toml, message, script):
    (tmp_path / "armctl.toml").write_text(toml)
    commands = [["status", "--once"], ["run", str(script), "--no-live"], ["estimate", str(script)]]
    if "sim://" in toml:
        commands.pop()  # estimate opens no port: the URL's options are never read
    for args in commands:
        result = _invoke(args)
        _no_traceback(result)
        assert result.exit_code == 2, (args, result.output)
        assert f"{tmp_path / 'armctl.toml'}" in result.output and message in result.output, result.output
        assert "using the built-in simulator" not in result.output
    if "sim://" not in toml:
        lint = _invoke(["lint", str(script)])
        assert lint.exit_code == 2 and message in lint.output, lint.output


def test_misspelt_keys_in_the_lint_and_jog_tables_get_a_did_you_mean(tmp_path, script):
    from armctl.jog.keymap import JogConfigError
    from armctl.jog.settings import settings_from_config

    (tmp_path / "armctl.toml").write_text('[lint]\nignre = ["L203"]\n')
    result = _invoke(["lint", script])
    assert result.exit_code == 2 and "unknown key 'lint.ignre' (did you mean 'ignore'?)" in result.output, result.output
    with pytest.raises(JogConfigError, match=r"jog\.step_nm is not a jog setting \(did you mean 'step_mm'\?\)"):
        settings_from_config({"step_nm": [1, 2, 3]}, "armctl.toml")


@pytest.mark.parametrize("args, env, message", [
    (["status", "--once", "--port", ""], {}, "--port is empty"),
    (["run", "{script}", "--no-live", "--port", " "], {}, "--port is empty"),
    (["status", "--once"], {"ARMCTL_PORT": ""}, "ARMCTL_PORT is set but empty"),
])
def test_an_empty_port_is_a_usage_error_through_the_installed_command(args, env, message, script, tmp_path):
    environ = {**{k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}, **env}
    done = subprocess.run([*ARMCTL, *(a.format(script=script) for a in args)], capture_output=True, text=True,
                          timeout=60, cwd=tmp_path, env=environ)
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert "using the built-in simulator" not in done.stderr


def test_no_port_anywhere_is_the_simulator_and_says_so():
    result = _invoke(["status", "--once", "--timeout", "0.5"])
    assert "using the built-in simulator" in result.output


# --- profile values ---------------------------------------------------------------------------------


def _profile_keys():
    """(section, key) of every numeric profile key, read from the schema."""
    from armctl.host.profile import default_profile_data

    defaults, keys = default_profile_data(), []
    for section, rule in PROFILE_SCHEMA.items():
        if isinstance(rule, dict):
            for key in rule:
                # a boolean or a word ([connector] kinematics_verified, control_frames) is not a number
                if section not in ("lint",) and key != "channels" and not isinstance(defaults[section][key], (bool, str)):
                    keys.append((section, key))
    return keys


TOML_VALUES = st.one_of(
    st.sampled_from(["nan", "-nan", "inf", "-inf", "1e308", "-1e308", "3.4028235e38", "-3.4028235e38", "0", "-1",
                     "1e-308", "5e-324", "9223372036854775807", '"abc"', "true", "[]"]),
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.integers(min_value=-(2**63), max_value=2**63 - 1).map(str),
)


def _toml_line(section: str, key: str, value: str) -> str:
    """Put ``value`` where a number goes: the key itself, one end of a pair, one entry of a list."""
    from armctl.host.profile import default_profile_data

    current = default_profile_data()[section][key]
    if isinstance(current, tuple):
        items = [repr(v) for v in current]
        items[0] = value
        return f'[{section}]\n{key} = [{", ".join(items)}]\n' if len(items) != 2 else \
            f'[{section}]\n{key} = [{value}, {repr(current[1])}]\n'
    if section == "poses":
        return f"[{section}]\n\"{key}\" = [{value}, 0, 0, 0, 90, 0]\n"
    return f"[{section}]\n{key} = {value}\n"


@pytest.mark.parametrize("section, key", _profile_keys())
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(value=TOML_VALUES)
def test_a_profile_value_is_accepted_or_refused_naming_the_file_and_key(section, key, value, script, tmp_path):
    path = tmp_path / "arm.toml"
    path.write_text(_toml_line(section, key, value))
    result = _invoke(["estimate", script, "--profile", path])
    _no_traceback(result)
    assert result.exit_code in (0, 1, 2), result.output
    if result.exit_code == 2:
        assert str(path) in result.output, result.output
    try:
        never_a_number = not math.isfinite(float(value))
    except ValueError:
        never_a_number = True  # text, a boolean, a list
    if never_a_number or abs(float(value)) >= 1e308:  # no key's range comes near 1e308
        assert result.exit_code == 2 and f"{path}: {section}.{key}" in result.output, result.output


@pytest.mark.parametrize("text, message", [
    ("[speed]\nmax_joint_deg_s = 1e308\n", "speed.max_joint_deg_s must be from 0.1 to 3600, not 1e+308"),
    ("[speed]\nmax_joint_deg_s = nan\n", "speed.max_joint_deg_s must be a number, not nan"),
    ("[speed]\nmax_linear_mm_min = inf\n", "speed.max_linear_mm_min must be a number, not inf"),
    ("[links]\nforearm_mm = 1e-300\n", "links.forearm_mm must be from 1 to 10000"),
    ("[timing]\njoint_ramp_s = [0.1, 0.1, 0.1, 0.1, 0.1, 3.4028235e38]\n", "timing.joint_ramp_s must be from 0 to 60"),
    ("[workspace]\nx_mm = [-inf, 100]\n", "workspace.x_mm must be a number, not -inf"),
    ("[timing]\npwm_change_s = 2.2e-309\n", "timing.pwm_change_s must be 0 or from 1e-06 to 60"),  # speeds overflowed
])
def test_reproducers_from_issue_10_are_located_profile_errors(text, message, script, tmp_path):
    path = tmp_path / "arm.toml"
    path.write_text(text)
    done = subprocess.run([*ARMCTL, "estimate", str(script), "--profile", str(path)], capture_output=True,
                          text=True, timeout=60, cwd=tmp_path)
    assert done.returncode == 2 and f"{path}: {message}" in done.stderr, done.stderr


# --- the motion model at the edges of what a profile accepts ----------------------------------------

MOTION_SCRIPT = """G6 J1=10 J2=5 J3=5 J4=0 J5=80 J6=0 S1500 F30 H3
G6 J1=10 J2=5 J3=5 J4=0 J5=80 J6=0 S1600 F30
POSE 1
POSE 0
G1 X200 Y0 Z300 A0 B0 C0 F600
G1 X200.001 F60000
G220 X180 K3200 F300
G300 X190 Y10 Z300 R10 F300
G301 X200 Y20 Z300 F300
G4 P1
G4 P0
POSE 2
"""


SPEED_AND_TIMING_EDGES = {
    ("speed", "max_linear_mm_min"): (1.0, 100_000.0),
    ("speed", "max_joint_deg_s"): (0.1, 3600.0),
    ("speed", "max_accel_mm_s2"): (1.0, 100_000.0),
    ("speed", "attitude_deg_s"): (0.1, 3600.0),
    ("timing", "command_overhead_s"): (1e-6, 60.0),  # or 0: see _edge_or_inside
    ("timing", "pwm_change_s"): (1e-6, 60.0),
    ("links", "base_height_mm"): (0.0, 10_000.0),
    ("links", "shoulder_offset_mm"): (-10_000.0, 10_000.0),
    ("links", "upper_arm_mm"): (1.0, 10_000.0),
    ("links", "elbow_offset_mm"): (-10_000.0, 10_000.0),
    ("links", "forearm_mm"): (1.0, 10_000.0),
    ("links", "tool_mm"): (0.0, 10_000.0),
}


def _edge_or_inside(low: float, high: float):
    """The default (None), an edge, or any float inside; a timing constant may also be 0."""
    edges = [low, high, None, *([0.0] if low == 1e-6 else [])]
    return st.one_of(st.sampled_from(edges), st.floats(min_value=low, max_value=high))


def test_the_edges_listed_here_are_the_schema_s():
    for (section, key), (low, high) in SPEED_AND_TIMING_EDGES.items():
        rule = PROFILE_SCHEMA[section][key]
        assert rule(low) == low and rule(high) == high
        for outside in (low - 1e-9 * max(1.0, abs(low)) - 1e-12, high * (1 + 1e-9)):
            with pytest.raises(Exception):
                rule(outside)


@settings(max_examples=150, deadline=None)
@given(choice=st.fixed_dictionaries({k: _edge_or_inside(*v) for k, v in SPEED_AND_TIMING_EDGES.items()}),
       ramp=_edge_or_inside(1e-6, 60.0))
def test_the_motion_model_gives_finite_times_for_any_accepted_profile(choice, ramp):
    from armctl.core.estimate import JobEstimator
    from armctl.core.motion import MotionModel
    from armctl.host.profile import parse_profile
    from armctl.script import compile_text

    data: dict = {}
    for (section, key), value in choice.items():
        if value is not None:
            data.setdefault(section, {})[key] = value
    if ramp is not None:
        data.setdefault("timing", {})["joint_ramp_s"] = [ramp] * 6
    profile = parse_profile(data, "<edges>")
    model = MotionModel(profile)
    estimator = JobEstimator(model, model.initial_pose())
    compilation = compile_text(MOTION_SCRIPT)
    for statement in compilation:
        assert math.isfinite(estimator.add(statement.command))
    assert compilation.error_count == 0
    result = estimator.result
    assert math.isfinite(result.job_s) and result.job_s > 0


@pytest.mark.parametrize("port, message", [
    ("sim://?loss=2", "--port: loss must be a number 0…1"),
    ("", "--port is empty"),
])
def test_jog_on_a_terminal_refuses_a_bad_port_with_exit_2(port, message, tmp_path):
    """jog checks stdin is a terminal first; on a real pty the port is the next thing checked."""
    master, slave = os.openpty()
    try:
        env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
        done = subprocess.run([*ARMCTL, "jog", "--port", port], stdin=slave, stdout=slave, stderr=slave,
                              cwd=tmp_path, env=env, timeout=60)
        os.set_blocking(master, False)
        screen = b""
        try:
            while chunk := os.read(master, 65536):
                screen += chunk
        except (BlockingIOError, OSError):
            pass
    finally:
        os.close(slave)
        os.close(master)
    text = screen.decode("utf-8", "replace")
    assert done.returncode == 2 and message in text, text
