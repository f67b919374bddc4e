"""Issue 22: where a regular file is meant, a named pipe, a device or a directory is refused
before it is opened — one line naming it, exit 2 — instead of an open that waits for a writer
(or a reader) for ever.  Through the installed command in a fresh process; a hang fails the test
at the subprocess timeout.  Stdin (``-``) stays the way to give a stream.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

ARMCTL = [sys.executable, "-m", "armctl"]
JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F6000\n"
TIMEOUT_S = 20
SIM = "sim://?clock=virtual"

pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")


@pytest.fixture
def place(tmp_path):
    (tmp_path / "job.txt").write_text(JOB)
    os.mkfifo(tmp_path / "pipe")
    return tmp_path


def armctl(args, cwd, input: bytes | None = None):
    done = subprocess.run([*ARMCTL, *map(str, args)], capture_output=True, timeout=TIMEOUT_S, cwd=cwd, input=input,
                          stdin=None if input is not None else subprocess.DEVNULL,
                          env={k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"})
    return done.returncode, done.stdout.decode(), done.stderr.decode()


PIPE_AS = {
    "--profile": ["estimate", "--profile", "{f}", "job.txt"],
    "run --profile": ["run", "--dry-run", "--profile", "{f}", "job.txt"],
    "--resume": ["run", "job.txt", "--no-live", "--port", SIM, "--resume", "{f}"],
    "decode": ["decode", "{f}"],
    "--log": ["run", "job.txt", "--no-live", "--port", SIM, "--log", "{f}"],
    "sim://?profile=": ["run", "job.txt", "--no-live", "--port", SIM + "&profile={f}"],
    "status sim://?profile=": ["status", "--once", "--port", SIM + "&profile={f}"],
    "sim --url": ["sim", "--pty", "--url", "sim://?profile={f}"],
    "jog --log": ["jog", "--log", "{f}"],
}


@pytest.mark.parametrize("command", PIPE_AS.values(), ids=PIPE_AS.keys())
def test_a_named_pipe_is_refused_not_waited_on(place, command):
    code, _out, err = armctl([part.format(f="pipe") for part in command], place)
    assert code == 2, err
    assert "Traceback" not in err
    assert "pipe: a named pipe, not a regular file" in err.strip().splitlines()[-1], err


def test_a_named_pipe_named_by_armctl_toml_is_refused(place):
    (place / "armctl.toml").write_text('profile = "pipe"\n')
    code, _out, err = armctl(["estimate", "job.txt"], place)
    assert code == 2 and err.strip() == f"armctl: {place / 'pipe'}: a named pipe, not a regular file", err


@pytest.mark.parametrize("command", [["estimate", "--profile", "/dev/zero", "job.txt"], ["decode", "/dev/zero"],
                                     ["run", "job.txt", "--no-live", "--port", SIM, "--resume", "/dev/null"],
                                     ["decode", "."]], ids=" ".join)
def test_a_device_or_directory_is_refused(place, command):
    code, _out, err = armctl(command, place)
    assert code == 2, err
    assert err.strip().endswith(("a character device, not a regular file", "a directory, not a regular file")), err


def test_stdin_and_an_output_device_still_work(place):
    code, out, err = armctl(["decode", "-"], place, input=b"")
    assert code == 0, err
    code, out, err = armctl(["run", "job.txt", "--no-live", "--port", SIM, "--log", "/dev/null"], place)
    assert code == 0, err


def test_the_library_refuses_before_opening(place):
    from armctl.errors import ProfileError
    from armctl.host.inputs import NotARegularFile, open_regular, read_file_bounded
    from armctl.host.profile import load_profile

    pipe = str(place / "pipe")
    with pytest.raises(NotARegularFile, match="a named pipe"):
        open_regular(pipe)
    with pytest.raises(NotARegularFile, match="a named pipe"):
        read_file_bounded(pipe)
    with pytest.raises(NotARegularFile, match="NUL character"):
        read_file_bounded("a\0b")
    with pytest.raises(ProfileError, match="a named pipe"):
        load_profile(pipe)
    assert read_file_bounded(str(place / "job.txt")) == JOB.encode()


def test_the_api_refuses_a_named_pipe_as_resume(place):
    from armctl import Arm
    from armctl import ResumeRefused

    with Arm.open(SIM) as arm:
        with pytest.raises(ResumeRefused, match="a named pipe"):
            arm.run(place / "job.txt", resume=place / "pipe")
