"""Ctrl-C in a program that drives the arm through the Python API (docs/api.md: no signal handler
is installed; Ctrl-C raises KeyboardInterrupt in the main thread).

A program that caught the KeyboardInterrupt out of ``arm.run`` and went on, inside its ``with``
block, left the job running: the arm ran every frame to the end (found by a review: 601 of 601
frames, 42 s, after a Ctrl-C at 1 s).  ``run`` now stops the job it started, as ``armctl run``'s
Ctrl-C does; leaving the block by the same Ctrl-C does not stop it a second time (a second
stop cuts the wait for the arm to come to rest short).  A real SIGINT, in a fresh process.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

from armctl.host.arm_tasks import Tasks

pytestmark = pytest.mark.timeout(60)

PROGRAM = r'''
import os, signal, threading, time
from armctl import Arm
job = "G90\nG1 X250 Y-50 Z150 A180 B0 C0 F3000 S1000\nO<a> repeat [300]\nG1 Z100 F3000\nG1 Z150\nO<a> endrepeat\n"
sent = [0]
with Arm.open("sim://?speed=20") as arm:
    threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
    start = time.monotonic()
    try:
        arm.run(job, on_progress=lambda progress: sent.__setitem__(0, progress.frames_sent))
        print("not interrupted")
    except KeyboardInterrupt:
        arm.wait()  # the worker is free once the stopped job has ended
        print(f"stopped: {sent[0]} of 601 frames, the worker free after {time.monotonic() - start:.1f} s")
'''


def test_a_ctrl_c_caught_around_run_stops_the_job_it_started():
    done = subprocess.run([sys.executable, "-c", PROGRAM], capture_output=True, text=True, timeout=50)
    assert done.returncode == 0, done.stdout + done.stderr
    words = done.stdout.split()
    assert words[0] == "stopped:", done.stdout
    frames, free_s = int(words[1]), float(words[-2])
    assert frames < 300 and free_s < 20, done.stdout  # (601 frames and 42 s before: the job ran to its end)


class _Stopping:
    """A job control that counts the stops asked of it (armctl/host/arm_worker.py's JobControl)."""

    def __init__(self) -> None:
        self.stop_asked, self.asked = False, 0

    def request_stop(self, why=None) -> None:
        self.stop_asked, self.asked = True, self.asked + 1


def test_stop_once_does_not_ask_a_stopping_job_again_and_stop_does():
    tasks = Tasks("sim://")
    try:
        job = tasks.job = _Stopping()
        tasks.stop_once()
        tasks.stop_once()  # Ctrl-C leaving the with block after run() stopped the job: the same stop
        assert job.asked == 1
        tasks.stop()  # arm.stop() called again: a second stop, which cuts the wait short
        assert job.asked == 2
    finally:
        tasks.job = None
        tasks.worker.stop()
