"""Where armctl writes what the user names (``compile -o``, ``run --log``, stdout): never over the
script, never by replacing what is not a regular file, and never a silent success on a full disk.

Found by an adversarial review of issue 10: ``compile -o /dev/null`` as root replaced the device
with a regular file, ``-o`` through a symlink or onto a FIFO replaced them, ``run --log job.txt``
and ``compile - -o job.txt < job.txt`` wrote over the script, ``compile > /dev/full`` exited 0.
Fresh processes (the installed command), each bounded by a timeout.
"""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import threading

import pytest

ARMCTL = [sys.executable, "-m", "armctl"]
SCRIPT = "G1 X250 Y0 Z150 A180 B0 C0 S1500 F3000\nG4 P10\n"
ENV = {key: value for key, value in os.environ.items() if key != "ARMCTL_PORT"}


def armctl(*args, stdin=None, stdout=subprocess.PIPE, cwd=None):
    return subprocess.run([*ARMCTL, *map(str, args)], stdin=stdin, stdout=stdout, stderr=subprocess.PIPE,
                          timeout=60, env=ENV, cwd=cwd)


@pytest.fixture
def job(tmp_path):
    path = tmp_path / "job.txt"
    path.write_text(SCRIPT)
    return path


def frames_of(job) -> bytes:
    done = armctl("compile", job)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_compile_through_a_symlink_writes_its_target_and_keeps_the_link(job, tmp_path):
    (tmp_path / "target.hex").write_text("old\n")
    link = tmp_path / "out.hex"
    link.symlink_to("target.hex")
    done = armctl("compile", job, "-o", link)
    assert done.returncode == 0, done.stderr
    assert link.is_symlink() and (tmp_path / "target.hex").read_bytes() == frames_of(job)


def test_compile_onto_a_fifo_writes_through_it(job, tmp_path):
    """A FIFO (like a device: not a regular file) is written through, never replaced."""
    fifo = tmp_path / "frames.fifo"
    os.mkfifo(fifo)
    received = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()), daemon=True)
    reader.start()
    done = armctl("compile", job, "-o", fifo)
    reader.join(30)
    assert done.returncode == 0, done.stderr
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert received == [frames_of(job)]


def test_an_output_in_a_missing_folder_names_the_users_path(job, tmp_path):
    done = armctl("compile", job, "-o", tmp_path / "nowhere" / "x.hex")
    assert done.returncode == 2
    assert f"{tmp_path / 'nowhere' / 'x.hex'}: No such file or directory" in done.stderr.decode()
    assert b".tmp" not in done.stderr


@pytest.mark.parametrize("how", ["same path", "symlink", "stdin"])
def test_compile_never_writes_over_its_script(job, tmp_path, how):
    before = job.read_bytes()
    if how == "stdin":
        with open(job, "rb") as stdin:
            done = armctl("compile", "-", "-o", job, stdin=stdin)
    else:
        output = job
        if how == "symlink":
            output = tmp_path / "link.txt"
            output.symlink_to(job)
        done = armctl("compile", job, "-o", output)
    assert done.returncode == 2 and b"it is the script itself" in done.stderr
    assert job.read_bytes() == before


@pytest.mark.parametrize("how", ["same path", "symlink"])
def test_run_log_never_writes_over_its_script(job, tmp_path, how):
    before = job.read_bytes()
    log = job
    if how == "symlink":
        log = tmp_path / "log.jsonl"
        log.symlink_to(job)
    done = armctl("run", job, "--port", "sim://?clock=virtual", "--no-live", "--log", log)
    assert done.returncode == 2 and b"--log" in done.stderr and b"it is the script itself" in done.stderr
    assert job.read_bytes() == before


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full on this system")
@pytest.mark.parametrize("command", [["compile", "{job}"], ["decode", "{job}"], ["lint", "{job}", "--json"]])
def test_a_full_disk_on_stdout_is_an_error_not_a_success(job, command):
    with open("/dev/full", "wb") as full:
        done = armctl(*(part.format(job=job) for part in command), stdout=full)
    assert done.returncode == 2, done.stderr
    assert b"No space left on device" in done.stderr and b"Traceback" not in done.stderr


@pytest.mark.parametrize("args", [["run", "{job}", "--baud", "2999", "--port", "sim://?clock=virtual"],
                                  ["status", "--once", "--port", "sim://?clock=virtual&baud=2400"]])
def test_a_line_too_slow_for_the_status_stream_is_refused(job, args):
    """9 status bytes every 30 ms need 3000 bit/s: on a slower line the arm's reports fall ever
    further behind and a run would judge the job on stale positions."""
    done = armctl(*(part.format(job=job) for part in args))
    assert done.returncode == 2 and b"3000" in done.stderr, done.stderr
