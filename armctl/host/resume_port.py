"""The port a resume goes to: the one its log's job ran on.

Strategy: a job's ``--log`` records its port (the job record's ``port``, armctl/core/joblog.py);
a resume must reach that arm, not whatever port is configured today.  ``resume_port`` chooses
the port ``armctl run --resume`` opens: without ``--port``, the log's (ARMCTL_PORT and
armctl.toml are for new jobs); with ``--port``, that one only if it is the same arm
(``same_arm``: the same URL, or the same ``calibration.arm_identity`` — a device by its USB
serial number, a ``sim://`` URL by the options that make its arm), or ``--other-port`` says it
is (the arm moved to another port); a log written before armctl recorded its port resumes on
the port given or configured, as it did, with a note saying the port is unknown.
``refuse_another_arm`` is the rule itself, for ``Arm.run(resume=)`` too, before anything is sent.

A ``sim://`` arm lives in the armctl process that opened it and dies with it: a resume in
another process would meet a new arm at its home pose, whose reports prove nothing of the lines
the old one ran (it "resumed" from where the new arm stands, or said every line was proven
executed).  So the log of a ``sim://`` job names its process (``simulator_process``: the pid and
a random mark, as a pid can come again), and ``refuse_gone_simulator`` refuses (exit 2) a resume
from any other — ``--other-port`` or not: no port reaches that arm any more.
"""

from __future__ import annotations

import os
import uuid

from ..errors import ArmctlError, ResumeRefused, UsageFailure
from .port_choice import SIMULATOR_URL

OVERRIDE_FLAG = "--other-port"
_PROCESS_MARK = uuid.uuid4().hex[:16]  # this process's, once: with the pid, what no later process has


def simulator_process(url: str) -> str | None:
    """The process the arm on ``url`` lives and dies in, for a ``sim://`` port (this one); None
    for any other port (a device, a network port, ``armctl sim --pty``: the arm outlives us)."""
    return f"{os.getpid()}-{_PROCESS_MARK}" if url.startswith(SIMULATOR_URL) else None


def refuse_gone_simulator(point) -> None:
    """``ResumeRefused`` (exit 2, nothing sent) when the log ``point`` was read from records a job
    on a simulated arm of another process: that arm is gone, and no report of a new one proves
    which lines ran."""
    if point.sim_process is None or point.sim_process == simulator_process(SIMULATOR_URL):
        return
    name = point.log_path or "the log"
    raise ResumeRefused(
        f"--resume {name}: its job ran on a simulated arm ({point.port}) of another armctl process, which has "
        "ended: a simulated arm does not outlive its process, and the one a resume would open now starts afresh "
        "at its home pose, so none of its reports can prove which lines ran; nothing was sent (run the job "
        "again; to try a resume, keep a simulated arm in a process of its own: `armctl sim --pty` or "
        "`armctl sim --tcp PORT`, and its port as --port)")


def same_arm(logged: str, url: str) -> bool:
    """The arm on ``url`` is the one on ``logged`` (a log's port)."""
    if logged == url:
        return True
    from .calibration import arm_identity

    try:
        return arm_identity(logged) == arm_identity(url)
    except ArmctlError:  # a URL it cannot read (ConfigError): not shown to be the same arm
        return False


def refuse_another_arm(point, url: str, override: str) -> None:
    """``ResumeRefused`` (exit 2, nothing sent) when the log ``point`` was read from records its
    job on another arm than the one on ``url``; ``override``: how to say it is the same arm."""
    if point.port is None or same_arm(point.port, url):
        return
    name = point.log_path or "the log"
    raise ResumeRefused(f"--resume {name}: its job ran on {point.port}, not on {url}: a resume on another arm "
                        f"would continue a job that arm never ran; nothing was sent (leave out --port to resume on "
                        f"{point.port}, or, if the arm on {url} is that arm moved to another port, {override})")


def resume_port(point, option: str | None, other_port: bool = False):
    """The port ``armctl run --resume`` opens for the log ``point`` (``option``: --port, None when
    not given) and what to tell the user about it: (a ``PortChoice``, the note or None, the point —
    re-aimed at the port given when ``other_port`` says it is the same arm)."""
    from dataclasses import replace

    from .port_choice import choose_port

    name = point.log_path or "the log"
    if other_port and option is None:
        raise UsageFailure(f"{OVERRIDE_FLAG} says the arm of --resume {name} is now on --port: give --port")
    if point.port is None:
        choice = choose_port(option)
        origin = "the built-in simulator, no port configured" if choice.origin == "default" else f"from {choice.origin}"
        return choice, (f"--resume: {name} does not record the port its job ran on (an armctl before this one wrote "
                        f"it): resuming on {choice.url} ({origin}); be sure that is the arm the job ran on"), point
    if option is None:
        return choose_port(point.port, origin=f"--resume {name}"), \
            f"--resume: on the port {name} records, {point.port} (the arm its job ran on)", point
    choice = choose_port(option)
    if other_port:
        return choice, f"--resume: on {choice.url} ({OVERRIDE_FLAG}: the arm {name} ran on, at {point.port})", \
            replace(point, port=choice.url)
    refuse_another_arm(point, choice.url, f"add {OVERRIDE_FLAG}")
    return choice, None, point
