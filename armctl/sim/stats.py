"""What the simulated arm saw, as JSON: for a benchmark in another process (``armctl sim --stats``).

Strategy: the simulator's own records — every frame that landed (its arrival time, accepted or
dropped), every frame the arm took (start, end, outcome) — in model seconds, with the clock
reading at model time 0 (``RealtimeArm.clock_start_s``: ``time.monotonic`` is one clock for
every process of the machine), so a host can place its own moments (an abort) on the arm's time.
The records are the simulator's recent window (``connector.HISTORY_FRAMES``); ``complete`` says
whether they hold the whole run.
"""

from __future__ import annotations

import json

from .model import SimulatedArm


def sim_stats(model: SimulatedArm, clock_start_s: float | None, time_scale: float = 1.0) -> dict:
    """The records of ``model`` as plain data (see the module docstring)."""
    return {
        "baud": model.options.baud,
        "time_scale": time_scale,
        "clock_start_s": clock_start_s,
        "now_s": model.now_s,
        "complete": model.history_complete,
        "dropped": model.frames_dropped,
        "bad_frames": model.bad_frames,
        "frames": [[f.index, f.arrival_s, f.accepted] for f in model.frames_received],
        "executions": [[e.index, e.start_s, e.end_s, e.outcome] for e in model.execution_log],
    }


def write_stats(path: str, model: SimulatedArm, clock_start_s: float | None, time_scale: float = 1.0) -> None:
    with open(path, "w", encoding="utf-8") as out:
        json.dump(sim_stats(model, clock_start_s, time_scale), out)
