"""``armctl probe``: find out, on the connected arm, what the vendor document leaves open.

Map: plan.py (the engine: steps as generators over status frames and ``now``), steps.py
(listen, H1/H8 and the status frame through G54, control-frame timing, restore), stream.py
(the status stream: its period and rotation, when each frame read was built), fifo.py (the
connector's capacity), landing.py (when frames landed, as the port's reports prove it),
motion.py (speed factor, kinematics; the timed moves), overhead.py (the wait before every
command), host.py (the loop over a Link), report.py (table, JSON, armctl.toml), command.py (the
click command).
docs/probe.md explains each measurement.
"""

from __future__ import annotations

SETTINGS = ("fifo_frames", "control_frames", "status_xyz_frame", "speed_factor", "kinematics_verified",
            "speed_tolerance", "command_overhead_s")


# How late a status frame's timestamp may be on a real port: the link's reader wakes every 20 ms,
# and a USB serial adapter holds bytes up to ~16 ms (FTDI's default latency timer).
REAL_PORT_TIMESTAMP_UNCERTAINTY_S = 0.04
# Bytes a real port may still hold after its driver counts them as sent (``out_waiting`` 0): a
# USB serial adapter's own transmit FIFO (FT232R 256 B, CP2102 640 B, FT232H 1 KB).  A frame is
# proven landed only this many byte times after the port said it had left (armctl/probe/landing.py).
# The simulator counts a byte as unsent until it has landed: 0 there.
ADAPTER_FIFO_BYTES = 1024


def build_probe(profile, baud: int, start_s: float, motion: bool, virtual_clock: bool = False,
                after_sent_bytes: int = ADAPTER_FIFO_BYTES):
    """The probe's steps in order (motion only if allowed), ending with the restore step.
    ``virtual_clock``: status timestamps are exact (``sim://?clock=virtual``);
    ``after_sent_bytes``: bytes the port may hold after it reports them sent."""
    from . import fifo, motion as motion_steps, steps, stream
    from .plan import Probe

    plan = [("listening to the status", steps.listen), ("checking the encoding (G54)", steps.encoding),
            ("control frames (pause behind a delay)", steps.control), ("FIFO capacity", fifo.fifo),
            ("kinematics at rest", motion_steps.kinematics_at_rest)]
    if motion:
        plan += [("speed factor (small moves)", motion_steps.speed_factor)]
    plan += [("kinematics", motion_steps.kinematics_finding), ("status stream", stream.status_stream)]
    probe = Probe(plan, steps.restore, baud, start_s, after_sent_bytes)
    probe.profile, probe.motion_allowed = profile, motion
    probe.timestamp_uncertainty_s = 0.0 if virtual_clock else REAL_PORT_TIMESTAMP_UNCERTAINTY_S
    return probe
