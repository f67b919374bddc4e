"""Cost of one status frame in the streamer against the number of frames pending.

``python benchmarks/streamer_cost.py`` builds two streamers that have written tiny moves (1 mm at
6000 mm/min, 10 ms each) — one with 9 frames pending, one with 185 — and feeds each the same
kind of status frame: the arm's position a little way along the first pending move (the usual
case: the streamer's lower bound lags the arm by a frame or two).  It times batches of frames
on the two alternately and prints the median of the per-pair ratios cost(185)/cost(9): flat
means about 1.  Ratios from one run only (the machine drifts; pairs cancel the drift).
"""

from __future__ import annotations

import statistics
import sys
import time

from armctl.bench.scenarios import tiny_moves
from armctl.core.motion import MotionModel
from armctl.host.profile import load_profile
from armctl.core.protocol import JointsLowStatus, PositionStatus
from armctl.core.streamer import Streamer

PAIRS = 31
BATCH = 200  # status frames per timed batch


def loaded_streamer(pending: int):
    """A streamer with ``pending`` tiny moves written, the first of them (after a long move from
    home) under way; returns it and a status frame placing the arm on that first move."""
    model = MotionModel(load_profile())
    streamer = Streamer(model, model.initial_pose(), lead_s=60.0, capacity=1000)
    commands = tiny_moves(pending + 1)
    now = 0.0
    for command in commands:
        streamer.wrote(command, now)
        now += streamer.frame_s
    streamer._ledger.consume_one(by_reports=True)  # the long move from home is known done: the tiny moves remain
    first = streamer.pending[0].segment
    x, y, z = first.sample(first.duration_s * 0.4).xyz
    return streamer, [PositionStatus(x, y, z), JointsLowStatus(0.0, 0.0, 0.0)], now


def batch_seconds(streamer, frames, now: float) -> float:
    started = time.perf_counter()
    for k in range(BATCH):
        streamer.receive_status(frames[k % len(frames)], now)
    return time.perf_counter() - started


def main() -> int:
    small, small_frames, small_now = loaded_streamer(9)
    large, large_frames, large_now = loaded_streamer(185)
    assert len(small.pending) == 9 and len(large.pending) == 185
    ratios = []
    for k in range(PAIRS):
        if k % 2:
            a = batch_seconds(small, small_frames, small_now)
            b = batch_seconds(large, large_frames, large_now)
        else:
            b = batch_seconds(large, large_frames, large_now)
            a = batch_seconds(small, small_frames, small_now)
        ratios.append(b / a)
    assert len(large.pending) == 185, "the probe must not consume frames"
    per_frame_us = batch_seconds(small, small_frames, small_now) / BATCH * 1e6
    print(f"streamer cost per status frame, 185 pending ÷ 9 pending: {statistics.median(ratios):.2f} "
          f"(median of {PAIRS} alternating pairs of {BATCH} frames; 9 pending: {per_frame_us:.0f} µs a frame)")
    print("reproduce: python benchmarks/streamer_cost.py")
    return 0


if __name__ == "__main__":
    sys.exit(main())
