"""The benchmark table: every scenario × every pacing strategy, in virtual time.

Strategy: one *cell* is one scenario run twice through one strategy against a fresh simulated
arm — once to the end (frames dropped, job time, true peak FIFO occupancy, peak queued motion
seconds) and once aborted at mid-job (the host stops after half the frames and writes a pause
frame; how long the arm keeps moving).  Cells are independent, so they run in parallel
processes.  Job times are divided by the omniscient strategy's job time in the same scenario.
armctl's own rows are checked against the targets of DESIGN.md / issue 5:

- no frame dropped (in either run);
- job time ≤ the scenario's bound × omniscient (1.01 arm- and line-bound, 1.03 the rest);
- motion after the abort ≤ lead × the arm's true slowness (speed_factor, if above 1) + the move
  in progress + the time the abort frame itself takes to reach the arm (one frame on the wire).
  "The move in progress" is the longer (true duration) of the frame the arm was executing when
  the abort frame was written and the last frame written before it: to keep the arm fed, a
  move longer than the lead must be written while the one before it still runs, so an abort
  just after that write leaves both to finish.

The abort run leaves out a scenario's outside events (the pause scenario's pause and resume):
they are pause toggles too, and would toggle against the abort's pause.

``main`` runs and prints the table for ``armctl bench`` (whose options live in armctl/cli.py;
``python -m armctl.bench`` is the same click command); it returns 1 when armctl misses a target
anywhere.
"""

from __future__ import annotations

import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field, replace

from ..motion import MotionModel
from ..protocol import frame_seconds
from ..sim.model import SimulatedArm
from ..streamer import DEFAULT_LEAD_S
from .harness import RunResult, run_job
from .scenarios import Scenario, build_scenarios, physical_bound_s
from .strategies import (
    FixedDelayStrategy, NaiveStrategy, OmniscientStrategy, StopAndGoStrategy, StreamerStrategy,
)

STRATEGY_NAMES = ("armctl", "naive", "fixed delay", "stop-and-go", "omniscient")
FIXED_DELAY_S = 0.1  # the fixed-delay baseline: a frame every 100 ms, a common hand-tuned value


def make_strategy(name: str, arm: SimulatedArm, lead_s: float, fixed_delay_s: float = FIXED_DELAY_S):
    """A fresh strategy for ``arm``; armctl's and stop-and-go plan with the nominal model."""
    baud = arm.options.baud
    # The host's model: the arm's own profile, as a probe finds it — its kinematics checked
    # (kinematics_verified; the simulated arm's links are the profile's), its speed_factor not
    # known (that is what the scenarios of a slower or faster arm measure).
    profile = arm.profile
    model = MotionModel(replace(profile, connector=replace(profile.connector, kinematics_verified=True)))
    if name == "armctl":
        return StreamerStrategy(model, arm.pose, lead_s, baud)
    if name == "naive":
        return NaiveStrategy(baud)
    if name == "fixed delay":
        return FixedDelayStrategy(fixed_delay_s, baud)
    if name == "stop-and-go":
        return StopAndGoStrategy(model, arm.pose, baud)
    if name == "omniscient":
        return OmniscientStrategy(arm, arm.options.fifo_frames, baud)
    raise ValueError(f"no strategy {name!r}; choose from {', '.join(STRATEGY_NAMES)}")


@dataclass
class Cell:
    scenario: str
    strategy: str
    frames: int
    dropped: int
    job_s: float
    peak_occupancy: int
    peak_queued_s: float
    moving_after_abort_s: float | None
    abort_limit_s: float | None  # armctl's target for moving_after_abort_s
    abort_dropped: int = 0
    timed_out: bool = False
    ratio: float | None = None  # job_s ÷ omniscient job_s, filled in by run_bench
    ratio_bound: float | None = None
    physical_s: float | None = None  # the physical bound of the job (PROTOCOL.md's last section)
    physical_ratio: float | None = None  # job_s ÷ physical_s, filled in by run_bench (as physical_s)
    physical_bound: float | None = None  # armctl's target for physical_ratio (None: none)
    failures: list[str] = field(default_factory=list)


def _in_progress_s(arm: SimulatedArm, at_s: float) -> float:
    """True duration of the segment the arm was executing at ``at_s`` (0 if none)."""
    for execution in arm.execution_log:
        if execution.start_s <= at_s and execution.end_s is not None and execution.end_s > at_s:
            return execution.end_s - execution.start_s
    return 0.0


def _duration_of_arrival(arm: SimulatedArm, index: int) -> float:
    """True duration of the frame that arrived ``index``-th (0 if it never ran to its end)."""
    for execution in arm.execution_log:
        if execution.index == index and execution.end_s is not None:
            return execution.end_s - execution.start_s
    return 0.0


def run_cell(scenario: Scenario, strategy: str, lead_s: float = DEFAULT_LEAD_S,
             fixed_delay_s: float = FIXED_DELAY_S, abort: bool = True) -> Cell:
    arm = SimulatedArm(scenario.options)
    full: RunResult = run_job(scenario.commands, make_strategy(strategy, arm, lead_s, fixed_delay_s), arm,
                              events=scenario.events)
    moving = limit = None
    abort_dropped = 0
    if abort:
        arm, line = SimulatedArm(scenario.options), []
        aborted = run_job(scenario.commands, make_strategy(strategy, arm, lead_s, fixed_delay_s), arm,
                          abort_after_frames=scenario.frames // 2, line=line)
        moving, abort_dropped = aborted.moving_after_abort_s, aborted.dropped
        slowness = max(1.0, scenario.options.speed_factor)
        frame_s = frame_seconds(scenario.options.baud)
        last_written = max(k for k, source in enumerate(line) if source == "job")
        longest = max(_in_progress_s(arm, aborted.aborted_at_s), _duration_of_arrival(arm, last_written))
        limit = lead_s * slowness + longest + frame_s
    return Cell(scenario.name, strategy, scenario.frames, full.dropped, full.job_s, full.peak_occupancy,
                full.peak_queued_s, moving, limit, abort_dropped, full.timed_out)


def _run_cell_args(args) -> Cell:
    return run_cell(*args)


def run_bench(scenarios: list[Scenario], strategies=STRATEGY_NAMES, lead_s: float = DEFAULT_LEAD_S,
              fixed_delay_s: float = FIXED_DELAY_S, jobs: int | None = None, abort: bool = True) -> list[Cell]:
    """Every cell, in scenario × strategy order, with ratios and armctl's target checks."""
    strategies = list(strategies)
    if "omniscient" not in strategies:
        strategies.append("omniscient")  # the reference for the ratio
    work = [(scenario, strategy, lead_s, fixed_delay_s, abort) for scenario in scenarios for strategy in strategies]
    jobs = jobs or min(len(work), os.cpu_count() or 1)
    if jobs > 1:
        # Longest first, so the pool does not end waiting on one slow cell.
        order = sorted(range(len(work)), key=lambda i: -work[i][0].frames)
        with ProcessPoolExecutor(jobs) as pool:
            results = dict(zip(order, pool.map(_run_cell_args, [work[i] for i in order])))
        cells = [results[i] for i in range(len(work))]
    else:
        cells = [run_cell(*w) for w in work]
    by_scenario = {s.name: s for s in scenarios}
    reference = {c.scenario: c.job_s for c in cells if c.strategy == "omniscient"}
    # the floor depends on the job alone: planned once per scenario, not once per strategy
    floor_s = {s.name: physical_bound_s(s.commands, s.options, s.outside_stop_s) for s in scenarios}
    for cell in cells:
        cell.ratio = cell.job_s / reference[cell.scenario] if reference[cell.scenario] else None
        cell.ratio_bound = by_scenario[cell.scenario].ratio_bound
        cell.physical_s = floor_s[cell.scenario]
        cell.physical_ratio = cell.job_s / cell.physical_s
        cell.physical_bound = by_scenario[cell.scenario].physical_bound
        if cell.strategy == "armctl":
            cell.failures = check_targets(cell)
    return cells


def check_targets(cell: Cell) -> list[str]:
    """What an armctl cell misses of its targets (empty when it meets them all)."""
    failures = []
    if cell.timed_out:
        failures.append("timed out")
    if cell.dropped or cell.abort_dropped:
        failures.append(f"dropped {cell.dropped + cell.abort_dropped} frame(s)")
    if cell.ratio is not None and cell.ratio_bound is not None and cell.ratio > cell.ratio_bound + 1e-9:
        failures.append(f"job time {cell.ratio:.3f} × omniscient > {cell.ratio_bound:.2f}")
    if cell.physical_bound is not None and cell.physical_ratio > cell.physical_bound + 1e-9:
        failures.append(f"job time {cell.physical_ratio:.3f} × the physical bound > {cell.physical_bound:.2f}")
    if cell.moving_after_abort_s is not None and cell.moving_after_abort_s > cell.abort_limit_s + 1e-9:
        failures.append(f"moved {cell.moving_after_abort_s:.2f} s after the abort > {cell.abort_limit_s:.2f} s")
    return failures


# --- output -----------------------------------------------------------------------------------

HEADERS = ("scenario", "strategy", "frames", "dropped", "time ÷ omni", "time ÷ physical", "peak occupancy",
           "peak queued s", "moving after abort s", "armctl targets")


def _row(cell: Cell) -> tuple[str, ...]:
    moving = "—" if cell.moving_after_abort_s is None else f"{cell.moving_after_abort_s:.2f}"
    if cell.strategy == "armctl" and cell.abort_limit_s is not None:
        moving += f" (≤ {cell.abort_limit_s:.2f})"
    dropped = str(cell.dropped) + (f" (+{cell.abort_dropped})" if cell.abort_dropped else "")
    ratio = "—" if cell.ratio is None else f"{cell.ratio:.3f}"
    physical = "—" if cell.physical_ratio is None else f"{cell.physical_ratio:.3f}"
    if cell.strategy == "armctl":
        if cell.ratio_bound is not None:
            ratio += f" (≤ {cell.ratio_bound:.2f})"
        if cell.physical_bound is not None:
            physical += f" (≤ {cell.physical_bound:.2f})"
        verdict = "met" if not cell.failures else "MISSED: " + "; ".join(cell.failures)
    else:
        verdict = ""
    return (cell.scenario, cell.strategy, str(cell.frames), dropped, ratio, physical, str(cell.peak_occupancy),
            f"{cell.peak_queued_s:.2f}", moving, verdict)


def format_table(cells: list[Cell]) -> str:
    rows = [HEADERS] + [_row(c) for c in cells]
    widths = [max(len(r[k]) for r in rows) for k in range(len(HEADERS))]
    numeric = {2, 3, 6, 7}
    lines = []
    previous = None
    for n, row in enumerate(rows):
        if n > 1 and row[0] != previous:
            lines.append("")
        previous = row[0] if n else None
        cells_text = [
            (text.rjust(widths[k]) if k in numeric and n else text.ljust(widths[k])) for k, text in enumerate(row)
        ]
        lines.append("  ".join(cells_text).rstrip())
        if n == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)


def summary(cells: list[Cell], scenarios: list[Scenario], lead_s: float, wall_s: float) -> str:
    missed = [c for c in cells if c.failures]
    lines = [
        f"lead {lead_s:g} s; fixed delay {FIXED_DELAY_S * 1000:g} ms; abort run: pause frame written after half "
        "the frames; dropped (+n) = frames dropped in the abort run.",
    ]
    for scenario in scenarios:
        if scenario.note:
            lines.append(f"{scenario.name}: {scenario.note}")
    invalid = sorted({c.scenario for c in cells if c.strategy == "omniscient" and c.dropped})
    if invalid:
        lines.append("WARNING: the omniscient reference dropped frames in " + ", ".join(invalid))
    lines.append(f"{len(cells)} cells in {wall_s:.1f} s wall time.")
    if missed:
        lines.append(f"armctl MISSED its targets in {len(missed)} scenario(s): "
                     + ", ".join(c.scenario for c in missed))
    else:
        lines.append("armctl: 0 frames dropped and every target met in every scenario.")
    return "\n".join(lines)


def main(size: str = "full", scenario_names=(), lead_s: float = DEFAULT_LEAD_S, as_json: bool = False,
         jobs: int | None = None) -> int:
    """Run the table and print it (or its cells as JSON); 1 when armctl misses a target anywhere.
    The command line is ``armctl bench`` (armctl/cli.py); ``python -m armctl.bench`` runs it too."""
    if not lead_s > 0:
        raise ValueError("the lead must be greater than 0")
    scenarios = [s for s in build_scenarios(size) if not scenario_names or s.name in scenario_names]
    started = time.perf_counter()
    cells = run_bench(scenarios, lead_s=lead_s, jobs=jobs)
    wall_s = time.perf_counter() - started
    if as_json:
        json.dump({"lead_s": lead_s, "size": size, "wall_s": round(wall_s, 2),
                   "cells": [asdict(c) for c in cells]}, sys.stdout, indent=1, ensure_ascii=False)
        print()
    else:
        print(format_table(cells))
        print()
        print(summary(cells, scenarios, lead_s, wall_s))
    return 1 if any(c.failures for c in cells) else 0
