"""The benchmark table: every scenario × every pacing strategy, in virtual time.

Strategy: one *cell* is one scenario run twice through one strategy against a fresh simulated
arm — once to the end (frames dropped, job time, true peak FIFO occupancy, peak queued motion
seconds) and once aborted at mid-job (the host stops after half the frames and writes a pause
frame; how long the arm keeps moving).  Cells are independent, so they run in parallel
processes.  Job times are divided by the omniscient strategy's job time in the same scenario.
armctl's own rows are checked against the targets of DESIGN.md / issue 5:

- no frame dropped (in either run);
- job time ≤ the scenario's bound × omniscient (1.01 arm- and line-bound, 1.03 the rest);
- job time ≤ 1.01 × the bound under the stop promise (``scenarios.promise_bound_s``: the best an
  omniscient host can do while keeping the promise below), on every row — so a row whose floor is
  the promise's, not the pacing's (``longfirst``), is judged too;
- motion after the abort ≤ the documented stop bound (README "Stopping a job"), in the arm's
  seconds: **the move in progress + max(lead, the next move)** — to keep the arm fed, a move
  longer than the lead must be queued before the current one ends, so an abort just after that
  write leaves both to finish.  ``stop_bound_s`` computes it from the job (each frame's true
  duration) and the abort moment (which frame the arm was executing), per run.

The arm-mismatch scenarios (``Scenario.probe``) run armctl twice: "armctl" plans with the
profile ``armctl probe`` finds on that arm (armctl/bench/probed.py), "armctl no probe" with the
document's defaults.  The probed row has the targets above (1.02 × omniscient) and, with
``Scenario.resume``, exactly-once across an abort and its resume on the same arm (every job frame
run once, by the simulator's execution log); the unprobed row only one: never "finished" (done)
after frames were lost (it may end "frames may have been lost", "finished, unproven" or "no
confirmation": the engine's outcomes that claim no more than the arm's reports prove).

The abort run leaves out a scenario's outside events (the pause scenario's pause and resume):
they are pause toggles too, and would toggle against the abort's pause.

``main`` runs and prints the table for ``armctl bench`` (whose options live in armctl/ui/cli.py;
``python -m armctl.bench`` is the same click command); it returns 1 when armctl misses a target
anywhere.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field, replace

from ..core.job import Outcome
from ..core.motion import MotionModel
from ..sim.executor import DONE
from ..sim.model import SimulatedArm
from ..core.streamer import DEFAULT_LEAD_S
from .harness import EPSILON_S, RunResult, run_job, start_run
from .scenarios import Scenario, build_scenarios, physical_bound_s, promise_bound_s, true_durations_s
from .strategies import (
    FixedDelayStrategy, NaiveStrategy, OmniscientStrategy, StopAndGoStrategy, StreamerStrategy,
)

STRATEGY_NAMES = ("armctl", "naive", "fixed delay", "stop-and-go", "omniscient")
NO_PROBE = "armctl no probe"  # the arm-mismatch scenarios' second armctl row: the document's defaults
FIXED_DELAY_S = 0.1  # the fixed-delay baseline: a frame every 100 ms, a common hand-tuned value
# armctl's job time ÷ the best any host keeping the stop promise could do (``promise_bound_s``), on
# every armctl row: the pacing's own cost, once the lead's price (longfirst) is no longer counted
PROMISE_RATIO = 1.01


def host_profile(scenario: Scenario, strategy: str):
    """The profile armctl's host plans with in an arm-mismatch scenario (None elsewhere): the
    probe's findings on that arm for "armctl", the document's defaults for "armctl no probe"."""
    if not scenario.probe or strategy not in ("armctl", NO_PROBE):
        return None
    from .probed import probed_profile, unprobed_profile

    return probed_profile(scenario.options) if strategy == "armctl" else unprobed_profile(scenario.options)


def make_strategy(name: str, arm: SimulatedArm, lead_s: float, fixed_delay_s: float = FIXED_DELAY_S, profile=None):
    """A fresh strategy for ``arm``; armctl's and stop-and-go plan with the nominal model.
    ``profile`` (an arm-mismatch scenario's armctl rows): plan with it, from where the arm
    reports it is (``armctl run``'s start), not from its true pose."""
    baud = arm.options.baud
    if profile is not None and name in ("armctl", NO_PROBE):
        model = MotionModel(profile)
        now = arm.snapshot()
        start = model.reported_pose(now.position_mm, now.joints_deg, now.pwm_us, now.origin_mm)
        return StreamerStrategy(model, start, lead_s, baud)
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
    promise_s: float | None = None  # the best any host keeping the stop promise can do (``promise_bound_s``)
    promise_ratio: float | None = None  # job_s ÷ promise_s, filled in by run_bench; armctl: ≤ PROMISE_RATIO
    outcome: str = ""  # the job engine's outcome of the whole run, as ``armctl run`` ends it
    not_once: list[int] | None = None  # resume scenarios: job frames (1-based) not run exactly once
    not_once_run: list[int] | None = None  # issue-9 scenarios: the same, in the whole run
    failures: list[str] = field(default_factory=list)


def stop_bound_s(arm: SimulatedArm, line: list[str], aborted_at_s: float, durations_s: list[float],
                 lead_s: float) -> float:
    """The documented stop bound, in the arm's seconds: the move in progress when the abort was
    written + max(lead, the next move).  ``line``: what each arrival index was (``run_job``),
    ``durations_s``: each job frame's true duration (``true_durations_s``).  The move in
    progress is the job frame the arm was executing at ``aborted_at_s`` (none if it was idle);
    the next move, the first frame after it (or after the last frame begun) that takes time."""
    job_frame = _job_frames(line)
    begun = [e for e in arm.execution_log if e.index in job_frame and e.start_s <= aborted_at_s + EPSILON_S]
    in_progress_s, after = 0.0, 0
    if begun:
        last = max(begun, key=lambda e: (e.start_s, e.index))
        after = job_frame[last.index]  # 1-based: the index of the frame after it
        if last.end_s is None or last.end_s > aborted_at_s + EPSILON_S:
            in_progress_s = durations_s[after - 1]
    next_move_s = next((d for d in durations_s[after:] if d > 0), 0.0)
    return in_progress_s + max(lead_s, next_move_s)


def run_cell(scenario: Scenario, strategy: str, lead_s: float = DEFAULT_LEAD_S,
             fixed_delay_s: float = FIXED_DELAY_S, abort: bool = True) -> Cell:
    profile = host_profile(scenario, strategy)

    def strategy_for(arm):
        return make_strategy(strategy, arm, lead_s, fixed_delay_s, profile)

    arm, line = SimulatedArm(scenario.options), []
    full: RunResult = run_job(scenario.commands, strategy_for(arm), arm, events=scenario.events, line=line)
    # an issue-9 row: every job frame ran exactly once in the whole run (the execution log)
    whole = frames_not_run_once(arm, _job_frames(line), scenario.frames) if scenario.probe else None
    moving = limit = None
    abort_dropped = 0
    if abort:
        arm, line = SimulatedArm(scenario.options), []
        aborted = run_job(scenario.commands, strategy_for(arm), arm, abort_after_frames=scenario.frames // 2, line=line)
        moving, abort_dropped = aborted.moving_after_abort_s, aborted.dropped
        limit = stop_bound_s(arm, line, aborted.aborted_at_s, true_durations_s(scenario.commands, scenario.options),
                             lead_s)
    cell = Cell(scenario.name, strategy, scenario.frames, full.dropped, full.job_s, full.peak_occupancy,
                full.peak_queued_s, moving, limit, abort_dropped, full.timed_out, outcome=full.outcome,
                not_once_run=whole)
    if scenario.resume and strategy in ("armctl", NO_PROBE):
        cell.not_once = not_run_once(scenario, strategy_for)
    return cell


def not_run_once(scenario: Scenario, strategy_for) -> list[int]:
    """Abort at mid-job, then resume on the same arm as ``armctl run --from-line N`` would (N the
    engine's resume line, after the engine settled): the job frames (1-based) the arm did not
    run exactly once, read from its execution log (frames that ran to their end)."""
    arm, line = SimulatedArm(scenario.options), []
    aborted = run_job(scenario.commands, strategy_for(arm), arm, abort_after_frames=scenario.frames // 2, line=line,
                      settle=True)
    frame_of = _job_frames(line)
    resume_at = aborted.resume_line or scenario.frames + 1
    if resume_at <= scenario.frames:
        strategy = strategy_for(arm)
        start_run(arm, line, strategy.streamer.control_on_arrival)
        first = len(line)
        run_job(scenario.commands[resume_at - 1:], strategy, arm, line=line)
        number = resume_at
        for index in range(first, len(line)):
            if line[index] == "job":
                frame_of[index], number = number, number + 1
    return frames_not_run_once(arm, frame_of, scenario.frames)


def _job_frames(line: list[str]) -> dict[int, int]:
    """Arrival index → job frame (1-based), for the job frames of one run (``run_job``'s ``line``)."""
    frame_of = {}
    for index, source in enumerate(line):
        if source == "job":
            frame_of[index] = len(frame_of) + 1
    return frame_of


def frames_not_run_once(arm: SimulatedArm, frame_of: dict[int, int], total: int) -> list[int]:
    """The job frames 1…``total`` that the arm did not run to their end exactly once, by its
    execution log (``frame_of``: arrival index → job frame)."""
    if not arm.history_complete:
        raise ValueError("the run is longer than the simulator's history")
    done = [frame_of[e.index] for e in arm.execution_log if e.index in frame_of and e.outcome == DONE]
    # The one repeat allowed (as tests/test_resume_exactly_once.py): the frame a pause froze on an
    # arm acting on arrival, re-sent by the resume — an absolute move to where the arm then is —
    # runs twice in a row.
    collapsed = [k for i, k in enumerate(done) if i == 0 or k != done[i - 1]]
    runs = Counter(collapsed if len(done) - len(collapsed) <= 1 else done)
    return [k for k in range(1, total + 1) if runs[k] != 1]


def _run_cell_args(args) -> Cell:
    return run_cell(*args)


def run_bench(scenarios: list[Scenario], strategies=STRATEGY_NAMES, lead_s: float = DEFAULT_LEAD_S,
              fixed_delay_s: float = FIXED_DELAY_S, jobs: int | None = None, abort: bool = True) -> list[Cell]:
    """Every cell, in scenario × strategy order, with ratios and armctl's target checks."""
    strategies = list(strategies)
    if "omniscient" not in strategies:
        strategies.append("omniscient")  # the reference for the ratio
    work = [(scenario, strategy, lead_s, fixed_delay_s, abort) for scenario in scenarios
            for strategy in strategies_for(scenario, strategies)]
    jobs = jobs or min(len(work), os.cpu_count() or 1)
    if jobs > 1:
        # Longest first, so the pool does not end waiting on one slow cell.
        order = sorted(range(len(work)), key=lambda i: -work[i][0].frames)
        # Spawned workers, not forked: a fork copies the threads' locks of a process that has other
        # threads (an API user's, a test run's), which may deadlock the child; Python 3.12+ warns.
        with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
            results = dict(zip(order, pool.map(_run_cell_args, [work[i] for i in order])))
        cells = [results[i] for i in range(len(work))]
    else:
        cells = [run_cell(*w) for w in work]
    by_scenario = {s.name: s for s in scenarios}
    reference = {c.scenario: c.job_s for c in cells if c.strategy == "omniscient"}
    # the floor depends on the job alone: planned once per scenario, not once per strategy
    floor_s = {s.name: physical_bound_s(s.commands, s.options, s.outside_stop_s) for s in scenarios}
    promise_s = {s.name: promise_bound_s(s.commands, s.options, lead_s, s.outside_stop_s) for s in scenarios}
    for cell in cells:
        cell.ratio = cell.job_s / reference[cell.scenario] if reference[cell.scenario] else None
        cell.ratio_bound = by_scenario[cell.scenario].ratio_bound
        cell.physical_s = floor_s[cell.scenario]
        cell.physical_ratio = cell.job_s / cell.physical_s
        cell.promise_s = promise_s[cell.scenario]
        cell.promise_ratio = cell.job_s / cell.promise_s
        cell.physical_bound = by_scenario[cell.scenario].physical_bound
        if cell.strategy == "armctl":
            cell.failures = check_targets(cell)
        elif cell.strategy == NO_PROBE:
            cell.failures = check_unprobed(cell)
    return cells


def strategies_for(scenario: Scenario, strategies) -> list[str]:
    """The rows of ``scenario``: an arm-mismatch scenario runs armctl with and without a probe
    (when armctl is asked for) and the omniscient reference only."""
    if not scenario.probe:
        return [s for s in strategies if s != NO_PROBE]
    rows = [s for s in strategies if s in ("armctl", "omniscient")]
    if "armctl" in rows:
        rows.insert(1, NO_PROBE)
    return rows


def check_unprobed(cell: Cell) -> list[str]:
    """The one target of armctl without a probe: never "finished" (done) after frames were lost
    (the simulator's count)."""
    if not (cell.dropped and cell.outcome == str(Outcome.FINISHED)):
        return []
    return [f"said done after {cell.dropped} frame(s) were lost"]


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
    if cell.promise_ratio is not None and cell.promise_ratio > PROMISE_RATIO + 1e-9:
        failures.append(f"job time {cell.promise_ratio:.3f} × the bound under the stop promise > {PROMISE_RATIO:.2f}")
    if cell.moving_after_abort_s is not None and cell.moving_after_abort_s > cell.abort_limit_s + 1e-9:
        failures.append(f"moved {cell.moving_after_abort_s:.2f} s after the abort > {cell.abort_limit_s:.2f} s")
    if cell.not_once_run:
        failures.append(not_once_text(cell.not_once_run, "whole run"))
    if cell.not_once:
        failures.append(not_once_text(cell.not_once, "resume"))
    return failures


def not_once_text(frames: list[int], where: str) -> str:
    shown = ", ".join(map(str, frames[:5])) + (" …" if len(frames) > 5 else "")
    return f"{where}: {len(frames)} job frame(s) not run exactly once ({shown})"


# --- output -----------------------------------------------------------------------------------

HEADERS = ("scenario", "strategy", "frames", "dropped", "time ÷ omni", "time ÷ physical", "time ÷ promise",
           "peak occupancy", "peak queued s", "moving after abort s", "armctl targets")


def _row(cell: Cell) -> tuple[str, ...]:
    moving = "—" if cell.moving_after_abort_s is None else f"{cell.moving_after_abort_s:.2f}"
    if cell.strategy in ("armctl", NO_PROBE) and cell.abort_limit_s is not None:
        moving += f" (≤ {cell.abort_limit_s:.2f})"
    dropped = str(cell.dropped) + (f" (+{cell.abort_dropped})" if cell.abort_dropped else "")
    ratio = "—" if cell.ratio is None else f"{cell.ratio:.3f}"
    physical = "—" if cell.physical_ratio is None else f"{cell.physical_ratio:.3f}"
    promise = "—" if cell.promise_ratio is None else f"{cell.promise_ratio:.3f}"
    if cell.strategy == "armctl" and cell.promise_ratio is not None:
        promise += f" (≤ {PROMISE_RATIO:.2f})"
    if cell.strategy == NO_PROBE:
        verdict = "; ".join(cell.failures) or f"met ({cell.outcome})"
        verdict = ("MISSED: " if cell.failures else "") + verdict
    elif cell.strategy == "armctl":
        if cell.ratio_bound is not None:
            ratio += f" (≤ {cell.ratio_bound:.2f})"
        if cell.physical_bound is not None:
            physical += f" (≤ {cell.physical_bound:.2f})"
        verdict = "met" if not cell.failures else "MISSED: " + "; ".join(cell.failures)
        if cell.not_once is not None and not cell.not_once:
            verdict += " (resume: every frame once)"
        if not cell.failures and cell.not_once_run == []:
            verdict = verdict.replace("met", "met (whole run: every frame once)", 1)
    else:
        verdict = ""
    return (cell.scenario, cell.strategy, str(cell.frames), dropped, ratio, physical, promise, str(cell.peak_occupancy),
            f"{cell.peak_queued_s:.2f}", moving, verdict)


def format_table(cells: list[Cell]) -> str:
    rows = [HEADERS] + [_row(c) for c in cells]
    widths = [max(len(r[k]) for r in rows) for k in range(len(HEADERS))]
    numeric = {2, 3, 7, 8}
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
        lines.append(f"armctl MISSED its targets in {len(missed)} row(s): "
                     + ", ".join(f"{c.scenario} ({c.strategy})" for c in missed))
    else:
        lines.append("armctl: 0 frames dropped and every target met in every scenario"
                     + ".")
    return "\n".join(lines)


def main(size: str = "full", scenario_names=(), lead_s: float = DEFAULT_LEAD_S, as_json: bool = False,
         jobs: int | None = None) -> int:
    """Run the table and print it (or its cells as JSON); 1 when armctl misses a target anywhere.
    The command line is ``armctl bench`` (armctl/ui/cli.py); ``python -m armctl.bench`` runs it too."""
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
