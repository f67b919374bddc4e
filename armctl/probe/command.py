"""``armctl probe``: the click command — options, consent to move, output, exit codes.

Strategy: only click at module level.  Everything that can refuse does so before the port
opens (a --write target that is not valid TOML: exit 2).  Motion needs consent: --yes, or a
"yes" typed on a terminal; otherwise the probe runs without motion and says so.  Exit codes:
0 done, 1 the arm contradicts the document in a way that stops the probe (H1/H8, no status),
2 usage, 130 interrupted (after restoring).
"""

from __future__ import annotations

import sys

import click

from ..ui.cli_types import NamedFile, number
from ..core.limits import BAUD_RANGE

MOTION_ANNOUNCEMENT = (
    "With your consent the probe moves the arm a little, slowly, and back: joint 5 by 5° at 2°/s, "
    "then (if the profile's kinematics match the arm) the tool 10 mm up at 300 mm/min. "
    "Everything else leaves the arm where it is (it changes the worktable origin, the gripper PWM "
    "by ≤ 100 µs and the pause state, and puts them back).")


# ``--forget`` alone (no command line can hold a NUL): the arm on --port, told from ``--forget ''``
ON_PORT = "\0"


@click.command(name="probe")
@click.option("--port", metavar="URL", help="Device path or pyserial URL (default: ARMCTL_PORT, armctl.toml, the simulator).")
@click.option("--baud", type=number(*BAUD_RANGE, whole=True), default=None, help="Line rate [default: 9600 or armctl.toml].")
@click.option("--no-motion", is_flag=True, help="Never move the arm (the speed factor is then not measured).")
@click.option("--yes", is_flag=True, help="Consent to the small moves without asking.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (the seven settings and details), nothing else.")
@click.option("--write", "write_path", type=NamedFile(dir_okay=False), metavar="FILE",
              help="Put the values into the [connector] table of FILE (an armctl.toml), keeping the rest.")
@click.option("--list", "list_stored", is_flag=True, help="List the arms probed and what was kept for each; probe nothing.")
@click.option("--forget", "forget", is_flag=False, flag_value=ON_PORT, default=None, metavar="[ARM]",
              help="Forget what was kept for ARM (an arm as --list names it, or a port; default: the arm on --port).")
def probe(port, baud, no_motion, yes, as_json, write_path, list_stored, forget):
    """Find out the arm's unknowns (FIFO size, control-frame timing, status frame, speed factor,
    its wait before every command, kinematics) and print them: setting, documented default, measured value, evidence, how sure.
    What it measured is kept with the arm (its USB serial number, host:port or sim:// options)
    and used by every command on that arm. See docs/probe.md."""
    if list_stored or forget is not None:
        from .keep import forget_arm, list_stored as listing

        if list_stored and forget is not None:
            raise click.UsageError("choose --list or --forget, not both")
        sys.exit(listing(as_json) if list_stored else forget_arm(None if forget == ON_PORT else forget, port))
    from .run import run_probe

    sys.exit(run_probe(port, baud, no_motion, yes, as_json, write_path, MOTION_ANNOUNCEMENT))
