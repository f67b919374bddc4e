"""Every input is bounded: unbounded work, endless inputs and files that change while read.

Strategy: these inputs can make a command hang or grow without limit, so every case runs the
installed command in a fresh process (``sys.executable -m armctl``) with a timeout and an
address-space limit: a hang or a runaway read fails that one test, never the suite or the
machine.  The contract (README, issue 10): a short script that would expand to unbounded work
is a located error before anything is sent; an endless input is a bounded read with a clear
message; what was checked is exactly what is written or sent, however the file changes.
The invariants themselves are ``check_outcome`` in tests/test_cli_properties.py.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from test_cli_properties import SUBPROCESS_TIMEOUT_S, check_outcome, fresh_env, limit_memory

LOCATED = re.compile(r"job\.txt:\d+:\d+")
SCRIPT_COMMANDS = (("lint",), ("compile", "--format", "hex"), ("estimate",), ("run", "--dry-run"))


def start(args, cwd: Path, stdin=subprocess.DEVNULL) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "armctl", *map(str, args)], stdin=stdin, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, cwd=cwd, env=fresh_env(), preexec_fn=limit_memory)


def finish(process: subprocess.Popen, args, timeout_s: float = SUBPROCESS_TIMEOUT_S) -> tuple[int, str, str]:
    try:
        stdout, stderr = process.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        pytest.fail(f"armctl {' '.join(map(str, args))}: no answer within {timeout_s} s (a hang)")
    out, err = stdout.decode("utf-8", "replace"), stderr.decode("utf-8", "replace")
    check_outcome([str(a) for a in args], process.returncode, out, err)
    return process.returncode, out, err


def armctl(args, cwd: Path, stdin=subprocess.DEVNULL) -> tuple[int, str, str]:
    return finish(start(args, cwd, stdin), args)


def write(directory: Path, text: str, name: str = "job.txt") -> Path:
    path = directory / name
    path.write_text(text, encoding="utf-8")
    return path


# --- unbounded work from a short script ------------------------------------------------------


def nested(depth: int, count: str) -> str:
    return ("".join(f"O<l{i}> repeat [{count}]\n" for i in range(depth)) + "G4 P1\n"
            + "".join(f"O<l{i}> endrepeat\n" for i in reversed(range(depth))))


UNBOUNDED = {
    "count 1e9": "O<a> repeat [1000000000]\nG4 P1\nO<a> endrepeat\n",
    "64 nested of 2": nested(64, "2"),
    "20 nested of 10": nested(20, "10"),
}


@pytest.mark.parametrize("command", SCRIPT_COMMANDS, ids=" ".join)
@pytest.mark.parametrize("name", UNBOUNDED)
def test_unbounded_expansion_is_a_located_error_not_a_hang(tmp_path, name, command):
    """(tests/test_input_trust.py: a count known only from an assignment.)"""
    code, stdout, stderr = armctl([*command, write(tmp_path, UNBOUNDED[name])], tmp_path)
    assert code == 1, f"{name}: exit {code}\n{stdout[-500:]}{stderr[-500:]}"
    assert LOCATED.search(stdout + stderr), f"{name}: the error is not located:\n{stdout[-500:]}{stderr[-500:]}"
    assert re.search(r"job\.txt:1:\d+: E012 ", stdout + stderr), f"{name}: not E012 on line 1:\n{stdout[-500:]}{stderr[-500:]}"


@pytest.mark.parametrize("count", ["3.4028235e38", "1e39", "inf", "nan", "-1", "0.5", "#<n>"])
def test_edge_repeat_counts_end_with_a_documented_exit(tmp_path, count):
    script = "#<n> = [1e12]\n" + f"O<a> repeat [{count}]\nG4 P1\nO<a> endrepeat\n"
    code, stdout, stderr = armctl(["compile", write(tmp_path, script)], tmp_path)
    if code == 1:
        assert LOCATED.search(stderr), stderr


@pytest.mark.parametrize("word", ["G4 P3e38", "G4 P3.4028235e38", "G1 X200 Y0 Z150 A180 B0 C0 S1000 F3000 U3e38"])
def test_a_move_or_delay_of_unbounded_arm_time_is_refused_before_run(tmp_path, word):
    """run on the virtual clock would otherwise wait out 3e38 ms of arm time."""
    script = write(tmp_path, word + "\n")
    code, stdout, stderr = armctl(["run", script, "--port", "sim://?clock=virtual", "--no-live"], tmp_path)
    assert code == 1, (stdout[-500:], stderr[-500:])


# --- endless inputs ---------------------------------------------------------------------------


ENDLESS_COMMANDS = (("lint",), ("compile",), ("estimate",), ("decode",), ("run", "--dry-run"))


@pytest.mark.parametrize("command", ENDLESS_COMMANDS, ids=" ".join)
def test_dev_zero_as_the_file(tmp_path, command):
    code, _stdout, _stderr = armctl([*command, "/dev/zero"], tmp_path)
    assert code in (1, 2)


@pytest.mark.parametrize("command", ENDLESS_COMMANDS, ids=" ".join)
def test_dev_zero_on_stdin(tmp_path, command):
    with open("/dev/zero", "rb") as zeros:
        code, _stdout, _stderr = armctl([*command, "-"], tmp_path, stdin=zeros)
    assert code in (1, 2)


@pytest.mark.parametrize("command", [("lint",), ("compile",), ("estimate",)], ids=" ".join)
def test_an_endless_stream_of_valid_lines_on_stdin(tmp_path, command):
    """A script that never ends (a generator piped in) is a bounded read too.  Its lines carry
    3 KB comments, so that any bound in bytes is reached within seconds (about 30 MB/s today)."""
    args = [*command, "-"]
    process = start(args, tmp_path, stdin=subprocess.PIPE)
    stop = threading.Event()

    def feed():
        chunk = (b"G4 P1 ; " + b"c" * 3000 + b"\n") * 100
        try:
            while not stop.is_set():
                process.stdin.write(chunk)
        except (BrokenPipeError, ValueError, OSError):
            pass

    writer = threading.Thread(target=feed, daemon=True)
    writer.start()
    try:
        code, _stdout, _stderr = _finish_with_open_stdin(process, args)
    finally:
        stop.set()
    assert code in (1, 2)


def _finish_with_open_stdin(process: subprocess.Popen, args):
    """communicate() would write to stdin itself; here a thread owns it, so only wait and read."""
    try:
        process.wait(timeout=SUBPROCESS_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
        pytest.fail(f"armctl {' '.join(map(str, args))}: no answer within {SUBPROCESS_TIMEOUT_S} s (a hang)")
    out = process.stdout.read().decode("utf-8", "replace")  # small: the process has ended
    err = process.stderr.read().decode("utf-8", "replace")
    check_outcome(args, process.returncode, out, err)
    return process.returncode, out, err


@pytest.mark.parametrize("args", [
    ("estimate", "--profile", "/dev/zero", "{script}"),
    ("lint", "--profile", "/dev/zero", "{script}"),
    ("status", "--once", "--port", "sim://?clock=virtual&profile=/dev/zero"),
], ids=["estimate --profile", "lint --profile", "sim profile"])
def test_an_endless_profile(tmp_path, args):
    script = write(tmp_path, "G4 P10\n")
    code, _stdout, stderr = armctl([a.format(script=script) for a in args], tmp_path)
    assert code == 2, stderr


# --- a file that changes while it is read -------------------------------------------------------


FRAMES = 3000
GOOD = "G4 P1\n" * FRAMES  # checks clean
BAD = "G4 P1\n" * (FRAMES // 2) + "G1 X500 Y400 Z-100\n" + "M3\n" * (FRAMES // 2)  # E004 on its line


class Rewriter:
    """Swaps a file between two versions as fast as it can, atomically (os.replace), until stopped:
    each open() sees one whole version, so a command that reads once sees GOOD or BAD."""

    def __init__(self, path: Path, versions: tuple[str, ...]):
        self.path, self.stop = path, threading.Event()
        self.staged = []
        for k, text in enumerate(versions):
            staged = path.with_name(f".{path.name}.{k}")
            staged.write_text(text, encoding="utf-8")
            self.staged.append(staged)
        self.thread = threading.Thread(target=self._swap, daemon=True)

    def _swap(self):
        k = 0
        while not self.stop.is_set():
            k += 1
            copy = self.path.with_name(f".{self.path.name}.copy")
            copy.write_bytes(self.staged[k % len(self.staged)].read_bytes())
            os.replace(copy, self.path)
            self.stop.wait(0.001)  # leave the CPU to the command under test

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join(5)


@pytest.fixture
def expected_hex(tmp_path) -> str:
    stable = write(tmp_path, GOOD, "stable.txt")
    code, stdout, stderr = armctl(["compile", "--format", "hex", stable], tmp_path)
    assert code == 0, stderr
    return stdout


def test_compile_writes_exactly_what_it_checked_while_the_file_is_swapped(tmp_path, expected_hex):
    """Exit 0 means the output is the whole of the clean version, never frames from the other."""
    path = write(tmp_path, GOOD)
    with Rewriter(path, (GOOD, BAD)):
        for _attempt in range(4):
            code, stdout, stderr = armctl(["compile", "--format", "hex", path], tmp_path)
            if code == 0:
                assert stdout == expected_hex, (f"exit 0 with {stdout.count(chr(10))} frames that are not the checked "
                                                f"script's {expected_hex.count(chr(10))}")


def test_run_sends_exactly_what_it_checked_while_the_file_is_swapped(tmp_path, expected_hex):
    """The --log of a job that ended 0 holds the clean version's frames, in order, and no other."""
    path, log = write(tmp_path, GOOD), tmp_path / "job.log"
    with Rewriter(path, (GOOD, BAD)):
        for _attempt in range(2):
            code, _stdout, stderr = armctl(["run", path, "--port", "sim://?clock=virtual", "--no-live",
                                            "--log", log], tmp_path)
            if code == 0:
                records = [json.loads(line) for line in log.read_text(encoding="utf-8").splitlines() if line.strip()]
                sent = [r["hex"] for r in records if r.get("dir") == "tx" and len(r.get("hex", "")) == 96]
                assert sent == expected_hex.split(), f"exit 0 but {len(sent)} frames sent, not the checked {FRAMES}"


@pytest.mark.parametrize("command", [("lint",), ("compile",), ("estimate",)], ids=" ".join)
def test_a_file_rewritten_in_place_while_read(tmp_path, command):
    """In-place rewrites (truncate, write) can show a reader a torn file: any outcome but a
    traceback or a hang is acceptable."""
    path = write(tmp_path, GOOD)
    stop = threading.Event()

    def rewrite():
        k = 0
        while not stop.is_set():
            k += 1
            with open(path, "w", encoding="utf-8") as handle:
                handle.write(GOOD if k % 2 else BAD)
            stop.wait(0.001)

    writer = threading.Thread(target=rewrite, daemon=True)
    writer.start()
    try:
        armctl([*command, path], tmp_path)
    finally:
        stop.set()
        writer.join(5)
