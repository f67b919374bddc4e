"""The ranges a number a user gives may take: one table for options, ``sim://`` and armctl.toml.

Strategy: every range a command-line option, a ``sim://`` option or an armctl.toml value is
checked against lives here once, as ``(low, high)`` with the unit in the name, so ``--baud``,
``baud =`` in armctl.toml and ``sim://?baud=`` cannot drift apart.  Pure constants, some derived from the link's (armctl/core/line.py).
"""

from __future__ import annotations

import math

from .line import BITS_PER_BYTE, STATUS_PERIOD_S, STATUS_SIZE

# bit/s.  The arm sends a 9-byte status frame every 30 ms (3000 bit/s at 8N1): on a slower line
# its status falls ever further behind, and a job judged on stale positions could be called done
# or lost wrongly.  The top is what pyserial and USB-serial adapters offer.
MIN_BAUD = math.ceil(STATUS_SIZE * BITS_PER_BYTE / STATUS_PERIOD_S - 1e-9)
BAUD_RANGE = (MIN_BAUD, 4_000_000)
LEAD_RANGE_S = (0.1, 60.0)  # motion queued ahead of the arm
BENCH_LEAD_RANGE_S = (0.001, 60.0)  # the benchmark may also show what a lead too short to feed the arm does
BENCH_JOBS_RANGE = (1, 64)  # parallel benchmark processes
STATUS_TIMEOUT_RANGE_S = (0.05, 600.0)  # waiting for the arm's first status
START_TIMEOUT_RANGE_S = (0.1, 600.0)  # waiting for the arm before a job or jog starts
JOB_TIMEOUT_RANGE_S = (0.001, 7 * 24 * 3600.0)  # the Python API's timeout= for a move or a job (arm seconds; a job may run 24 h)
LINE_RANGE = (1, 2**31 - 1)  # a line number in a script
TCP_PORT_RANGE = (1, 65535)
REPEAT_DELAY_RANGE_MS = (50.0, 5000.0)  # jog: a single key press moves at most this long

# The arm profile's [connector] table (armctl/host/profile.py), the arm's unknowns.  fifo_frames: from 3
# (under 8 the streamer keeps half of it free, not its 4-frame margin, and writes at least 2 ahead,
# an arc's two frames: streamer/constants.py ``limit_frames``; a probe keeps no smaller value); 4096
# frames (196 KB) is twenty times the document's 200 — a bigger number is a typo.  speed_factor:
# an arm 4× faster or slower than its profile says has the wrong profile, not a slow arm.
FIFO_RANGE_FRAMES = (3, 4096)
SPEED_FACTOR_RANGE = (0.25, 4.0)
# [connector] status_jitter_ms (and sim://?status_jitter_ms=): up to half the status period (beyond,
# a frame's slot in the stream is no longer told by its time)
STATUS_JITTER_RANGE_MS = (0.0, 15.0)

# sim:// options
SIM_TIME_SCALE_RANGE = (0.01, 1000.0)  # speed=: the simulated arm runs this many times faster
SIM_SLOWDOWN_RANGE = (0.1, 10.0)  # speed_factor= (slowdown=): motion takes this many times the model's time
SIM_FIFO_RANGE_FRAMES = (1, 100_000)  # fifo_frames= (fifo=): the connector's buffer (the document's holds 200)
SIM_LINK_SCALE_RANGE = (0.5, 2.0)  # link_scale=: the simulated arm's link lengths × this (kinematics mismatch)
SIM_SEED_RANGE = (0, 2**64 - 1)
SIM_RATE_RANGE = (0.0, 1.0)  # loss=, corrupt=, noise=: a share of status frames
SIM_WRITE_BUFFER_RANGE_BYTES = (48, 1 << 20)  # write_buffer_bytes=: host bytes held before the wire (a tty's is 4 KB)
SIM_READ_GRANULARITY_RANGE_MS = (0.0, 100.0)  # read_granularity_ms=: status bytes reach the host at ticks this far apart
