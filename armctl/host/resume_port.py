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

A name is not an arm: after a replug /dev/ttyUSB0 may be another arm, and the log's on
/dev/ttyUSB1.  So the job record keeps the identity of the arm as the job starts (``arm_of``:
``calibration.arm_identity``), and the port a resume opens, named by the log or by --port, must
have that identity now (the same USB serial number or location, the same path a by-id link
leads to); another is refused naming both, and the port where the log's arm is now found
(``_ports_of``: the devices pyserial lists, by identity) is the --port to give.  A log without
an identity (an older one) is checked by name as before; an identity that is only a path or an
address (a pty, a TCP port) proves no more than the name, and the note says so.

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
from .resume_words import CLI, ResumeWords

OVERRIDE_FLAG = "--other-port"
_PROCESS_MARK = uuid.uuid4().hex[:16]  # this process's, once: with the pid, what no later process has


def simulator_process(url: str) -> str | None:
    """The process the arm on ``url`` lives and dies in, for a ``sim://`` port (this one); None
    for any other port (a device, a network port, ``armctl sim --pty``: the arm outlives us)."""
    return f"{os.getpid()}-{_PROCESS_MARK}" if url.startswith(SIMULATOR_URL) else None


def refuse_gone_simulator(point, words: ResumeWords = CLI) -> None:
    """``ResumeRefused`` (exit 2, nothing sent) when the log ``point`` was read from records a job
    on a simulated arm of another process: that arm is gone, and no report of a new one proves
    which lines ran (told in ``words``: the interface's)."""
    if point.sim_process is None or point.sim_process == simulator_process(SIMULATOR_URL):
        return
    raise ResumeRefused(
        f"{words.naming(point.log_path)}: its job ran on a simulated arm ({point.port}) of another armctl process: a "
        "simulated arm does not outlive its process, and the one a resume would open here starts afresh "
        f"at its home pose, so none of its reports can prove which lines ran; nothing was sent ({words.again}; "
        "to try a resume, keep a simulated arm in a process of its own: `armctl sim --pty` or "
        f"`armctl sim --tcp PORT`, and {words.give_port})")


def arm_of(port, ports=None) -> str | None:
    """The identity of the arm on ``port`` (``calibration.arm_identity``: what a job record keeps as
    ``arm``): a ``PortChoice``'s, read once (``calibration.with_arm``), or a URL's now (``ports``:
    pyserial's list, read once); None for a URL it cannot read."""
    from .calibration import arm_identity

    if getattr(port, "arm", None) is not None:
        return port.arm.identity
    try:
        return arm_identity(getattr(port, "url", port), ports)
    except ArmctlError:  # a URL it cannot read (ConfigError)
        return None


def same_arm(logged: str, url: str, ports=None) -> bool:
    """The arm on ``url`` is the one on ``logged`` (a log's port), by name (a log without ``arm``)."""
    if logged == url:
        return True
    identity = arm_of(logged, ports)
    return identity is not None and identity == arm_of(url, ports)  # (unreadable: not shown to be the same arm)


def _ports_of(identity: str, logged: str, ports) -> list[str]:
    """The ports on which the arm of ``identity`` is found now: the log's port ``logged``, the
    devices pyserial lists (``ports``: ``armctl ports``), the path a device identity names."""
    from .calibration import ports_to_search

    candidates = [logged, *ports_to_search(identity, ports)]
    return list(dict.fromkeys(port for port in candidates if arm_of(port, ports) == identity))


def refuse_another_arm(point, port, override: str, ports=None, words: ResumeWords = CLI) -> None:
    """``ResumeRefused`` (exit 2, nothing sent) when the log ``point`` was read from records its
    job on another arm than the one on ``port`` (a ``PortChoice``, or a URL) — by the arm's
    identity the log recorded (``arm``), else by the port's name; ``override``: how to say it is
    the same arm; ``ports``: pyserial's list if read already (``_port_list``); ``words``: the interface's."""
    if point.port is None:
        return
    url = getattr(port, "url", port)
    if ports is None and getattr(port, "arm", None) is None:  # a URL's arm, read here
        ports = _port_list(url, point.port)
    now = arm_of(port, ports)
    if point.arm is not None and now is not None:
        if point.arm == now:
            return  # (a PortChoice's arm: no list read)
    else:
        ports = _port_list(url, point.port) if ports is None else ports
        if same_arm(point.port, url, ports):
            return
    ports = _port_list(url, point.port) if ports is None else ports  # where the log's arm is now
    name, logged = words.naming(point.log_path), words.on_logged_port.format(port=point.port)
    if point.arm is None or now is None:  # by name (a log without the identity)
        raise ResumeRefused(f"{name}: its job ran on {point.port}, not on {url}: a resume on another arm "
                            f"would continue a job that arm never ran; nothing was sent ({logged}, "
                            f"or, if the arm on {url} is that arm moved to another port, {override})")
    found = _ports_of(point.arm, point.port, ports)
    where = (f"{logged}, where that arm is" if point.port in found else
             f"that arm is on {found[0]} now: {words.on_port.format(port=found[0])}" if found else
             "that arm is not found on this host (`armctl ports` lists the ports): connect it and "
             f"{words.give_port}")
    now_there = f"{point.port} leads to another arm now, {now}" if url == point.port else f"{url} is {now}"
    raise ResumeRefused(f"{name}: its job ran on {point.port}, the arm {point.arm}; {now_there}: a resume on "
                        f"another arm would continue a job that arm never ran; nothing was sent ({where}; or, if the "
                        f"arm on {url} is that arm after all (on another adapter, say), {override})")


def _port_list(url: str, logged: str):
    """pyserial's list, read once for every identity of a resume's ports, and only where a device
    path needs it (``calibration.reads_port_list``)."""
    from .calibration import port_infos, reads_port_list

    return port_infos() if reads_port_list(url) or reads_port_list(logged) else ()


def _with_arm(choice, logged: str):
    """``choice`` with its arm read (``calibration.with_arm``) from the list of ports its resume
    reads once, and that list; a URL whose arm cannot be named stays as it is (``arm_of``: None)."""
    from .calibration import with_arm

    ports = _port_list(choice.url, logged)
    identity = arm_of(choice.url, ports)
    return (choice if identity is None else with_arm(choice, identity)), ports


def moved_to(point, url: str):
    """The log ``point`` re-aimed at ``url``: the caller's word that the arm its job ran on is
    there now (``--other-port``), whatever its name or identity."""
    from dataclasses import replace

    return replace(point, port=url, arm=None)


def resume_port(point, option: str | None, other_port: bool = False):
    """The port ``armctl run --resume`` opens for the log ``point`` (``option``: --port, None when
    not given) and what to tell the user about it: (a ``PortChoice``, the note or None, the point —
    re-aimed at the port given when ``other_port`` says it is the same arm)."""
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
        from .calibration import by_name_only

        choice, ports = _with_arm(choose_port(point.port, origin=f"--resume {name}"), point.port)
        refuse_another_arm(point, choice, f"--port {point.port} {OVERRIDE_FLAG}", ports)
        unchecked = ("its identity is unknown (an armctl before this one wrote the log): be sure it is still that arm"
                     if point.arm is None else
                     f"known as {point.arm} only, as any arm there would be: be sure it is still that arm"
                     if by_name_only(point.arm) else None)
        return choice, \
            f"--resume: on the port {name} records, {point.port} (the arm its job ran on" + \
            (f"; {unchecked})" if unchecked else ")"), point
    choice = choose_port(option)
    if other_port:
        return choice, f"--resume: on {choice.url} ({OVERRIDE_FLAG}: the arm {name} ran on, at {point.port})", \
            moved_to(point, choice.url)
    choice, ports = _with_arm(choice, point.port)
    refuse_another_arm(point, choice, f"add {OVERRIDE_FLAG}", ports)
    return choice, None, point
