"""Issue 22: a profile or armctl.toml that crashed the reader is one line naming the file and the
key, exit 2 — through the installed command in a fresh process.

Found by a generator of hostile inputs: ``pwm.channels = [[1]]`` (TypeError: a list is not
hashable), a 400-digit whole number in a profile, ``[connector]`` or ``[jog]`` (OverflowError
from math.isfinite), a 5,000-digit one (ValueError from tomllib's int()), an array 5,000 deep
(RecursionError in tomllib), ``profile = "a\\u0000b"`` (ValueError: embedded null byte from
open()), and a UTF-8 byte-order mark ("invalid TOML", while a script's BOM is dropped).
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from armctl.errors import ProfileError
from armctl.host.profile import parse_profile

ARMCTL = [sys.executable, "-m", "armctl"]
JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F6000\n"
TIMEOUT_S = 30
BIG = "9" * 400


def armctl(args, cwd):
    done = subprocess.run([*ARMCTL, *map(str, args)], capture_output=True, text=True, timeout=TIMEOUT_S, cwd=cwd,
                          env={k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"})
    return done.returncode, done.stdout, done.stderr


def one_line(stderr: str) -> str:
    assert "Traceback" not in stderr, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    return lines[0]


PROFILES = {
    "channels of lists": ("[pwm]\nchannels = [[1]]\n", "pwm.channels"),
    "400 digits": (f"[speed]\nmax_linear_mm_min = {BIG}\n", "speed.max_linear_mm_min"),
    "400 digits, negative": (f"[workspace]\nx_mm = [-{BIG}, 0]\n", "workspace.x_mm"),
    "400 digits in [connector]": (f"[connector]\nspeed_factor = {BIG}\n", "connector.speed_factor"),
    "5,000 digits": ("[speed]\nmax_linear_mm_min = " + "9" * 5000 + "\n", "invalid TOML"),
    "5,000 deep": ("[speed]\nmax_linear_mm_min = " + "[" * 5000 + "]" * 5000 + "\n", "nested"),
    "100 deep": ("x = " + "[" * 100 + "]" * 100 + "\n", "nested more than"),
}


@pytest.mark.parametrize("text, names", PROFILES.values(), ids=PROFILES.keys())
def test_a_bad_profile_is_one_line_naming_file_and_key(tmp_path, text, names):
    (tmp_path / "job.txt").write_text(JOB)
    (tmp_path / "arm.toml").write_text(text)
    code, _out, err = armctl(["estimate", "--profile", "arm.toml", "job.txt"], tmp_path)
    line = one_line(err)
    assert code == 2, err
    assert "arm.toml" in line and names in line, line


CONFIGS = {
    "400 digits in [connector]": (f"[connector]\nfifo_frames = {BIG}\n", "connector.fifo_frames"),
    "400 digits in [jog]": (f"[jog]\nstep_mm = [{BIG}]\n", "jog.step_mm"),
    "400 digits in [profile]": (f"[profile.speed]\nmax_linear_mm_min = {BIG}\n", "profile.speed.max_linear_mm_min"),
    "5,000 digits": ("baud = " + "9" * 5000 + "\n", "invalid TOML"),
    "5,000 deep": ("baud = " + "[" * 5000 + "]" * 5000 + "\n", "nested"),
    "NUL in the profile path": ('profile = "a\\u0000b"\n', "profile"),
}


@pytest.mark.parametrize("command", [["estimate", "job.txt"], ["config"]], ids=" ".join)
@pytest.mark.parametrize("text, names", CONFIGS.values(), ids=CONFIGS.keys())
def test_a_bad_armctl_toml_is_one_line_naming_file_and_key(tmp_path, text, names, command):
    (tmp_path / "job.txt").write_text(JOB)
    (tmp_path / "armctl.toml").write_text(text)
    code, _out, err = armctl(command, tmp_path)
    line = one_line(err)
    assert code == 2, err
    assert "armctl.toml" in line and names in line, line


def test_a_profile_with_a_byte_order_mark_is_read(tmp_path):
    (tmp_path / "job.txt").write_text(JOB)
    (tmp_path / "arm.toml").write_bytes(b"\xef\xbb\xbf[connector]\nfifo_frames = 150\n")
    code, _out, err = armctl(["estimate", "--json", "--profile", "arm.toml", "job.txt"], tmp_path)
    assert code == 0, err
    (tmp_path / "armctl.toml").write_bytes(b"\xef\xbb\xbfbaud = 19200\n")
    code, out, err = armctl(["config"], tmp_path)
    assert code == 0 and "19200" in out, err


def test_a_whole_number_past_a_float_given_to_the_api_is_a_profile_error():
    with pytest.raises(ProfileError, match="speed.max_linear_mm_min must be a number"):
        parse_profile({"speed": {"max_linear_mm_min": 10**400}})
