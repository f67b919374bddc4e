"""The edge of ``armctl probe``: consent, port, progress display, output, --write, exit code.

Strategy: the command (command.py) stays a few lines; this module wires the pure probe to a
Link (host.py) and to the terminal.  The progress display is a rich status line on a terminal,
a plain line per step elsewhere, nothing with --json (whose stdout is one JSON object).
"""

from __future__ import annotations

import json
import sys
import threading
from contextlib import contextmanager
from pathlib import Path

import click

from ..errors import EXIT_INTERRUPTED, EXIT_OK, EXIT_PROBLEMS


def decide_motion(no_motion: bool, yes: bool, say, announcement: str) -> bool:
    if no_motion:
        say("probe: --no-motion: the arm will not move; the speed factor is not measured")
        return False
    say(announcement)
    if yes:
        return True
    if not (sys.stdin.isatty() and sys.stderr.isatty()):
        say("probe: no terminal to ask and no --yes: probing without motion (the speed factor is not measured)")
        return False
    return click.confirm("Move the arm as described?", default=False, err=True)


@contextmanager
def progress_display(as_json: bool, say):
    """A callable the loop calls after each wait: shows the step and the arm time."""
    if as_json:
        yield None
        return
    if sys.stdout.isatty():
        from rich.console import Console

        with Console(stderr=True).status("probing…") as status:
            yield lambda probe: status.update(f"probing: {probe.current} — arm time {probe.arm_time_s:.1f} s")
        return
    shown = {"step": None}

    def update(probe):
        if probe.current != shown["step"]:
            shown["step"] = probe.current
            say(f"probe: {probe.current} (arm time {probe.arm_time_s:.1f} s)")

    yield update


def run_probe(port, baud, no_motion, yes, as_json, write_path, announcement) -> int:
    from ..host.link import SIMULATOR_URL, choose_port, connect
    from ..host.calibration import arm_profile
    from . import ADAPTER_FIFO_BYTES, build_probe
    from .host import FrameInbox, deferred_stop, drive
    from .report import as_json as json_object, print_lines, print_table
    from .toml_edit import check_writable, connector_table, toml_value, write_connector

    say = (lambda text: click.echo(text, err=True)) if as_json else click.echo
    target = Path(write_path) if write_path else None
    if target is not None:
        check_writable(target)  # before anything is sent: exit 2 if it is not valid TOML
    choice = choose_port(port)
    profile = arm_profile(port=choice.url)
    motion = decide_motion(no_motion, yes, say, announcement)
    inbox = FrameInbox()
    link, baud = connect(choice, baud, announce=say, profile=profile, on_status=inbox)
    stop = threading.Event()
    with link:
        probe = build_probe(profile, baud, link.clock(), motion, link.is_virtual,
                            after_sent_bytes=0 if link.url.startswith(SIMULATOR_URL) else ADAPTER_FIFO_BYTES)
        try:
            with deferred_stop(stop), progress_display(as_json, say) as update:
                drive(link, probe, inbox, update, stop)
        except KeyboardInterrupt:  # a second Ctrl-C while restoring: leave now, say what is left
            for note in probe.notes:
                click.echo(f"restore: {note}", err=True)
            click.echo("armctl: interrupted while restoring: the arm may not be as it was found "
                       f"(worktable origin {probe_origin(probe)}, PWM, pause state)", err=True)
            return EXIT_INTERRUPTED
    if as_json:
        click.echo(json.dumps(json_object(probe), indent=2, ensure_ascii=False))
    else:
        if sys.stdout.isatty():
            from rich.console import Console

            print_table(Console(), probe)
        else:
            print_lines(say, probe)
        for note in probe.notes:
            say(f"restore: {note}")
        say(f"arm time: {probe.arm_time_s:.1f} s")
    if target is not None and (probe.interrupted or probe.stopped is not None):
        say(f"--write: nothing written to {target} (the probe did not finish)")
    if probe.interrupted:
        click.echo("armctl: interrupted (the arm was restored first; see above)", err=True)
        return EXIT_INTERRUPTED
    if probe.stopped is not None:
        click.echo(f"armctl: probe stopped: {probe.stopped}", err=True)
        return EXIT_PROBLEMS
    from ..host.profile import MEASURED_ON
    from .keep import arm_identity, keep, measured_elsewhere, measured_on_arm, stated, written

    arm = arm_identity(choice.url)
    if target is not None:
        before = connector_table(target)
        values = written(arm, stated(probe, before if measured_on_arm(before, arm) else {}))  # (keep says what is not kept)
        drop = measured_elsewhere(before, arm, values)
        write_connector(target, values, drop)
        say(f"wrote [connector] in {target}: " + ", ".join(f"{k} = {toml_value(v)}" for k, v in values.items()))
        if drop:
            say(f"--write: took {', '.join(drop)} out of {target}: measured on another arm ({before[MEASURED_ON]})")
        if "fifo_frames" not in values:
            say(unmeasured_fifo_note(target, connector_table(target).get("fifo_frames")))
    keep(choice.url, arm, probe, say)  # with the arm: every command on it uses what was measured
    return EXIT_OK


def unmeasured_fifo_note(target, kept) -> str:
    """--write without a measured FIFO: what the file now says, and what to set by hand — a run
    must not stream into an unmeasured FIFO as if it held the document's 200 frames."""
    from .steps import DOCUMENTED

    if kept is not None:
        state = (f"{target} keeps fifo_frames = {kept!r} from before: it holds only if it was measured on this arm "
                 "and this connector")
    else:
        state = (f"{target} has none, so `armctl run` assumes the document's {DOCUMENTED['fifo_frames']} frames and "
                 "a smaller FIFO drops frames silently")
    return (f"--write: fifo_frames not written (not measured: see fifo_frames above); {state}. Set "
            "`[connector] fifo_frames = <the frames your connector holds>` by hand")


def probe_origin(probe) -> str:
    known = getattr(probe, "known", None)
    return "unknown" if known is None else f"was {known.origin_mm}"
