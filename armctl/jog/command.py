"""``armctl jog``: the click command — options, checks, exit codes; the loop is edge.py's.

Strategy: only click at module level (``armctl --help`` stays fast); everything else is imported
when the command runs.  Checks come before the arm can move: stdin must be a terminal (exit 2),
armctl.toml's ``[jog]`` table, the profile and the ``--record``/``--log`` paths must be usable
(exit 2), and the arm must report its pose within ``--timeout`` (exit 1, nothing sent).
Exit codes: 0 quit, 1 the arm or the port failed, 2 usage, 130 Ctrl-C.

Registered by the CLI with ``main.add_command(jog)``; ``python -m armctl.jog`` runs it alone.
"""

from __future__ import annotations

import sys

import click

from ..ui.cli_types import OutputFile, number
from ..core.limits import BAUD_RANGE, REPEAT_DELAY_RANGE_MS, START_TIMEOUT_RANGE_S

from ..errors import EXIT_PROBLEMS, EXIT_USAGE


def _fail(message: str, code: int):
    click.echo(f"armctl: {message}", err=True)
    sys.exit(code)


@click.command(name="jog")
@click.option("--port", "port", metavar="URL",
              help="Device path or pyserial URL (socket://, rfc2217://, sim://). "
              "Default: ARMCTL_PORT, else `port` in armctl.toml, else the built-in simulator.")
@click.option("--baud", type=number(*BAUD_RANGE, whole=True), default=None,
              help="Line rate [default: 9600 or `baud` in armctl.toml].")
@click.option("--mode", type=click.Choice(["joint", "linear"]), default="joint", show_default=True,
              help="Start jogging joints (q/a … y/h) or the tool along X/Y/Z (arrows, PgUp/PgDn).")
@click.option("--record", "record_path", type=OutputFile(), metavar="FILE",
              help="Append a G1 (linear mode) or G6 (joint mode) line per Enter to FILE.")
@click.option("--profile", "profile_path", type=click.Path(exists=True, dir_okay=False), help="Arm profile (TOML).")
@click.option("--log", "log_path", type=OutputFile(), metavar="FILE",
              help="JSON lines of every frame written and read, and every key (armctl decode reads it).")
@click.option("--repeat-delay", "repeat_delay_ms", type=number(*REPEAT_DELAY_RANGE_MS), default=None, metavar="MS",
              help="A single key press moves at most this long; set it to your keyboard's auto-repeat delay "
              "[default: 500 or `initial_delay_ms` in armctl.toml's [jog]].")
@click.option("--timeout", "timeout_s", type=number(*START_TIMEOUT_RANGE_S), default=3.0, show_default=True,
              help="Seconds to wait for the arm's status before refusing to jog.")
def jog(port, baud, mode, record_path, profile_path, log_path, repeat_delay_ms, timeout_s):
    """Move the arm from the keyboard and record poses into a script.

    Continuous jog is a dead-man switch: the axis moves while the key repeats and stops within
    150 ms of the last repeat (a single tap moves at most --repeat-delay). The key map is on
    screen; see docs/jog.md.
    """
    from ..errors import ArmctlError, ConfigError
    from ..host.posix_terminal import NeedsPosixTerminal, require_posix_terminal

    try:  # first: on Windows this, not a redirected stdin, is why jog cannot run
        require_posix_terminal("armctl jog", "run it under WSL, or on Linux or macOS")
    except NeedsPosixTerminal as error:
        _fail(str(error), EXIT_USAGE)
    if not sys.stdin.isatty():
        _fail("jog reads single key presses, and stdin is not a terminal: run it in a terminal "
              "(not through a pipe, a file or a script)", EXIT_USAGE)
    try:
        sys.exit(_jog(port, baud, mode, record_path, profile_path, log_path, repeat_delay_ms, timeout_s))
    except ConfigError as error:  # armctl.toml, or a port jog cannot use: like any usage error
        _fail(str(error), EXIT_USAGE)
    except ArmctlError as error:
        _fail(str(error), EXIT_PROBLEMS)
    except KeyboardInterrupt:
        _fail("interrupted", 130)


def _setup(profile_path, repeat_delay_ms, port=None):
    from dataclasses import replace

    from ..errors import ProfileError
    from ..host.calibration import arm_profile
    from ..host.profile import load_config
    from .keymap import JogConfigError
    from .settings import jog_from_config

    try:
        config = load_config()
        config_path = config.path_of("jog")
        settings, keymap = jog_from_config(config.values.get("jog", {}), str(config_path) if config_path else "armctl.toml")
        profile = arm_profile(profile_path, port=port)  # the arm's: its stored calibration laid over
    except (JogConfigError, ProfileError) as error:
        _fail(str(error), EXIT_USAGE)
    if repeat_delay_ms is not None:
        settings = replace(settings, initial_delay_ms=repeat_delay_ms)
    return settings, keymap, profile


def _open_files(record_path, log_path):
    from .edge import FrameLog, TeachFile

    teach = log = None
    try:
        teach = TeachFile(record_path) if record_path else None
        log = FrameLog(log_path) if log_path else None
    except OSError as error:
        if teach is not None:
            teach.close()
        _fail(f"cannot write {error.filename}: {error.strerror}", EXIT_USAGE)
    return teach, log


def _jog(port, baud, mode, record_path, profile_path, log_path, repeat_delay_ms, timeout_s) -> int:
    from ..host.link import choose_port, connect, require_wall_clock
    from ..core.protocol import frame_seconds
    from .edge import JogLoop, wait_for_pose
    from .keys import KeyDecoder
    from .session import JogSession

    choice = choose_port(port)
    settings, keymap, profile = _setup(profile_path, repeat_delay_ms, choice.url)
    teach, log = _open_files(record_path, log_path)
    try:
        from ..ui.output import announce

        link, baud = connect(choice, baud, announce=announce, profile=profile, on_status=log.rx if log else None)
        with link:
            require_wall_clock(link, "jog")
            problem = wait_for_pose(link, timeout_s)
            if problem is not None:
                click.echo(f"armctl: {problem}", err=True)
                return EXIT_PROBLEMS
            scale = link.clock.scale  # sim://?speed=N: the arm lives N× faster than the wall
            session = JogSession(settings, keymap, profile, mode, line_s=frame_seconds(baud) / scale,
                                 time_scale=scale, recording=teach is not None)
            loop = JogLoop(link, session, KeyDecoder(settings.escape_ms / 1000.0), profile=profile, keymap=keymap,
                           url=link.url, log=log, teach=teach, display=_display())
            outcome = loop.run(sys.stdin.fileno())
    finally:
        if teach is not None:
            teach.close()
        if log is not None:
            log.close()
    try:
        _summary(outcome, teach)
    except OSError:
        pass  # the terminal is gone: nobody to tell
    return outcome.exit_code


def _display():
    if not sys.stdout.isatty():
        return None
    from rich.console import Console
    from rich.live import Live
    from rich.text import Text

    return Live(Text("armctl jog: starting …"), console=Console(), auto_refresh=False, transient=False,
                redirect_stdout=False, redirect_stderr=False)


def _summary(outcome, teach) -> None:
    if teach is not None:
        poses = f"{outcome.recorded} pose{'s' if outcome.recorded != 1 else ''}"
        click.echo(f"armctl jog: {poses} recorded to {teach.path}")
    if outcome.unrecorded:
        click.echo(f"armctl jog: {outcome.unrecorded} pose(s) not recorded: the arm had not settled "
                   "when jog ended", err=True)
    if outcome.stop_failed:
        click.echo(f"armctl jog: {outcome.reason}; the stop could not be sent ({outcome.stop_failed}): "
                   "check the arm, it may still be moving", err=True)
    elif outcome.exit_code == 0:
        click.echo("armctl jog: quit; every axis was left at the neutral (stand-still) value")
    else:
        click.echo(f"armctl jog: {outcome.reason}; every axis was left at the neutral (stand-still) value", err=True)
