"""Crashed jobs for the journal's tests (tests/test_journal_*.py): a job run through the API on a
virtual-clock simulator, stopped after ``n`` frames with ``abort="none"`` (what a host that
died leaves: nothing more is sent, the arm runs out its queue), its ``--log`` kept as bytes.

``durable_end`` is what the write-ahead journal promises survives a power cut: the log up to
the end of the record of the last frame written (the last fsync before the crash).  ``ran`` is
the simulator's own record of what the arm executed (``SimulatedArm.execution_log``, reached as
``arm._link.port.model``): a frame it skipped (a G300 left alone) did not run.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from armctl import Arm
from armctl.script.files import read_script

VIRTUAL = "sim://?clock=virtual"
NOT_RUN = ("skipped", "ignored")


def ran(arm) -> list:
    """The commands the simulated arm executed, in order (its own record); ``arm``: an ``Arm``, or its port."""
    port = arm._link.port if isinstance(arm, Arm) else arm
    return [e.command for e in port.model.execution_log if e.command is not None and e.outcome not in NOT_RUN]


def sent(arm: Arm) -> int:
    """Frames the simulated arm received so far."""
    return len(arm._link.port.model.frames_received)


def job_commands(script: Path, from_line: int = 1) -> list:
    return [statement.command for statement in read_script(str(script)).compile(from_line=from_line)]


def crash_into(arm: Arm, script: Path, n: int, log: Path):
    """Run ``script`` on ``arm`` journalled to ``log`` and stop it after ``n`` frames, sending
    nothing more (the host died): the arm runs out its queue."""
    def stop(progress) -> None:
        if progress.frames_sent >= n:
            arm.stop()

    with log.open("w", encoding="utf-8") as file:
        return arm.run(script, on_progress=stop, log=file, abort="none")


@dataclass
class Crash:
    script: Path
    n: int
    log: bytes
    durable_end: int
    rest: tuple  # (position_mm, joints_deg) the arm reports at rest after the crash
    ran: list  # what the arm executed by then
    full: list  # the job's commands, every line once
    _correct: dict = field(default_factory=dict)

    def correct(self, line: int | None) -> bool:
        """Resuming at ``line`` (None: nothing) runs every line not yet executed exactly once."""
        if line not in self._correct:
            rest = [] if line is None else job_commands(self.script, line)
            self._correct[line] = self.ran + rest == self.full
        return self._correct[line]


def make_crash(script: Path, n: int, log: Path) -> Crash:
    with Arm.open(port=VIRTUAL) as arm:
        crash_into(arm, script, n, log)
        rest = at_rest(arm)
        executed = ran(arm)
    data = log.read_bytes()
    return Crash(script, n, data, durable_end(data), rest, executed, job_commands(script))


def at_rest(arm: Arm) -> tuple:
    """(position_mm, joints_deg) once the arm is at rest, as ``--resume`` waits for it."""
    from armctl.host.jobflow import wait_for_rest

    state = arm._call(lambda: wait_for_rest(arm._link, 600.0))
    return state.position_mm, tuple(state.joints_deg)


def durable_end(data: bytes) -> int:
    """The offset just past the record of the last job frame written (its record is fsynced
    before the frame is written; nothing after it need be)."""
    end, offset = 0, 0
    for line in data.split(b"\n")[:-1]:
        offset += len(line) + 1
        try:
            record = json.loads(line)
        except ValueError:
            continue
        if record.get("dir") in ("tx", "job"):
            end = offset
    return end


@contextmanager
def pty_arm(*options: str, env: dict | None = None):
    """``armctl sim --pty OPTIONS`` in a process of its own — an arm that outlives the armctl
    processes that drive it, as a real arm does (a ``sim://`` arm dies with its process): its
    pseudo-terminal's path; stopped (SIGINT, as Ctrl-C: its ``--stats`` are written) at the end."""
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"} if env is None else env
    sim = subprocess.Popen([sys.executable, "-m", "armctl", "sim", "--pty", *options], stdout=subprocess.PIPE,
                           text=True, env=env, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        yield re.search(r"(/dev/\S+)", sim.stdout.readline()).group(1)
    finally:
        sim.send_signal(signal.SIGINT)
        try:
            sim.wait(10)
        finally:
            sim.kill()
