"""The real-time benchmark (``armctl bench --realtime``): the bench's jobs on the wall clock.

Strategy: the virtual bench proves the pacing in model time; this one checks that the host keeps
it where the arm lives.  For each line rate (9600 and 115200 baud) and each job (arm-bound long
moves, line-bound tiny moves, the mixed job — shorter than the virtual bench's, so the whole
table takes about two minutes), ``armctl sim --pty --stats FILE`` runs the arm in another
process behind a real pseudo-terminal, with what real lines have (``LINE_OPTIONS``: a 4 KB
write buffer, status bytes handed over at 16 ms ticks as a USB adapter's latency timer does).
This process drives the job as ``armctl run`` does — ``read_arm``, then the job engine through
``JobRunner`` over a ``Link`` on the wall clock — once to its end and once aborted after half
its frames (a pause frame, H5).  When the arm process is stopped (SIGINT) it writes what it
saw (armctl/sim/stats.py); every figure comes from there, never from the host:

- **inter-arrival** — the job frames' mean time apart as they landed at the arm (50 ms at 9600
  is the line; more means the host wrote late);
- **÷ physical** — the job's time (from its first frame's first byte to the end of its last
  frame) over its physical bound (``scenarios.physical_bound_s``), and the same for the job
  run in virtual time through the virtual bench's harness (``table.run_cell``), row by row;
- **dropped** — frames the arm's FIFO discarded (both runs);
- **moving after abort** — from the host's stop (placed on the arm's clock: ``time.monotonic``
  is one clock for the machine) to the end of the arm's last motion, against the stop bound
  (``table.stop_bound_s``: the move in progress + max(lead, the next move)).

Targets: ÷ physical ≤ 1.01 for arm-bound jobs and the mixed one, ≤ 1.02 line-bound (the tiny
moves at 9600), at both rates; real time within 2 % of virtual time; no drop; the stop bound.
``main`` prints the table and returns 1 on a missed target.  Wall-clock figures move with the
machine's load: the table prints the load average it ran under.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field, replace
from types import SimpleNamespace

from ..core.protocol import PauseToggle, frame_seconds
from ..sim.model import SimOptions
from ..core.streamer import DEFAULT_LEAD_S
from .harness import Frame
from .scenarios import Scenario, long_moves, mixed_job, physical_bound_s, tiny_moves, true_durations_s

RATES = (9600, 115200)
LINE_OPTIONS = "write_buffer_bytes=4096&read_granularity_ms=16"
ARM_BOUND_RATIO = 1.01  # job ÷ physical bound, arm-bound and mixed jobs
LINE_BOUND_RATIO = 1.02  # ... line-bound ones
AGREE_SHARE = 0.02  # real time within this share of virtual time, row by row
START_TIMEOUT_S = 10.0  # the simulator process printing its pty, the arm answering
SIM_EXIT_TIMEOUT_S = 10.0


def realtime_jobs() -> list[tuple[str, tuple]]:
    """(name, commands): the virtual bench's generators, sized for about two minutes in all."""
    return [("long", tuple(long_moves(6))), ("tiny", tuple(tiny_moves(120))), ("mixed", tuple(mixed_job(1)))]


@dataclass
class RealtimeRow:
    baud: int
    job: str
    frames: int
    bound_kind: str  # "arm-bound", "line-bound" or "mixed"
    target: float
    inter_arrival_ms: float
    frame_ms: float
    physical_s: float
    job_s: float
    ratio: float
    virtual_ratio: float
    dropped: int
    abort_dropped: int
    moving_after_abort_s: float | None
    stop_bound_s: float | None
    virtual_moving_after_abort_s: float | None
    outcome: str
    failures: list[str] = field(default_factory=list)


def _bound_kind(name: str, commands, options: SimOptions) -> str:
    if name == "mixed":
        return "mixed"
    motion_s = sum(true_durations_s(commands, options))
    return "line-bound" if len(commands) * frame_seconds(options.baud) > motion_s else "arm-bound"


def _start_sim(url: str, stats_path: str) -> tuple[subprocess.Popen, str]:
    """``armctl sim --pty`` in another process (the installed package, as ``python -m armctl``);
    the pty's path from its first line."""
    process = subprocess.Popen([sys.executable, "-m", "armctl", "sim", "--pty", "--url", url, "--stats", stats_path],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = process.stdout.readline()  # "simulated arm on /dev/pts/N (Ctrl-C to stop)"
    if not line.startswith("simulated arm on "):
        process.kill()
        raise RuntimeError(f"armctl sim --pty did not start: {line.strip() or process.stderr.read().strip()}")
    return process, line.split()[3]


def _stop_sim(process: subprocess.Popen, stats_path: str) -> dict:
    process.send_signal(signal.SIGINT)  # it writes its stats, then exits 130
    try:
        process.wait(SIM_EXIT_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        raise RuntimeError("armctl sim did not stop on SIGINT") from None
    with open(stats_path, encoding="utf-8") as stats:
        return json.load(stats)


def _host_model(options: SimOptions):
    """The model armctl's host plans with: the virtual bench's (``table.make_strategy``) — the
    arm's own profile, kinematics checked, its speed_factor not known."""
    from ..core.motion import MotionModel
    from ..sim.model import _arm_profile

    profile = _arm_profile(options)
    return MotionModel(replace(profile, connector=replace(profile.connector, kinematics_verified=True)))


def drive(path: str, commands, baud: int, lead_s: float, abort_after: int | None) -> float | None:
    """Run ``commands`` on the arm at ``path`` as ``armctl run`` does (``drive_on``), planning
    with the virtual bench's host model."""
    from ..host.link import Link, plausible_state

    model = _host_model(SimOptions(baud=baud))
    with Link.open(path, baud, state=plausible_state(model.profile)) as link:
        return drive_on(link, model, commands, baud, lead_s, abort_after)


def drive_on(link, model, commands, baud: int, lead_s: float, abort_after: int | None) -> float | None:
    """Run ``commands`` through ``link`` as ``armctl run`` does (read the arm, then the job engine
    on the link's clock), planning with ``model``; with ``abort_after``, stop once that many
    frames are written, as Ctrl-C does (the abort sequence: one pause frame).  The link's clock
    when the stop was asked (None without one)."""
    from ..core.job import RunView
    from ..core.checked import start_from_state
    from ..host.jobflow import read_arm
    from ..host.runner import JobRunner
    from ..core.streamer import Streamer

    stopped_at: list[float] = []
    start, _initial = start_from_state(model, read_arm(link, START_TIMEOUT_S))
    streamer = Streamer(model, start, lead_s=lead_s, baud=baud)
    view = RunView(total_frames=len(commands), estimated_job_s=0.0, lead_s=lead_s, capacity=streamer.limit_frames)
    statements = (Frame(command, k + 1) for k, command in enumerate(commands))
    runner: JobRunner

    def on_update(view) -> None:
        if abort_after is not None and view.frames_sent >= abort_after and not runner.stop_requested:
            stopped_at.append(link.clock.now())
            runner.request_stop()

    runner = JobRunner(link, streamer, statements, view, on_update=on_update)
    link.on_status = runner.on_status  # (as Arm.run wires it)
    try:
        try:
            runner.run()
        except KeyboardInterrupt:
            runner.abort((PauseToggle(),))
    finally:
        link.on_status = None
    return stopped_at[0] if stopped_at else None


def _job_figures(stats: dict, frames: int, baud: int) -> tuple[float, float, float]:
    """(mean inter-arrival s, job s, last motion end s) of the job frames the arm saw."""
    arrivals = [arrival for index, arrival, _ in stats["frames"] if index < frames]
    first_byte_s = arrivals[0] - frame_seconds(baud)
    ends = [end for index, _start, end, _ in stats["executions"] if index < frames and end is not None]
    mean_s = (arrivals[-1] - arrivals[0]) / (len(arrivals) - 1) if len(arrivals) > 1 else 0.0
    return mean_s, max(ends) - first_byte_s, max(ends)


def moving_frames(commands, options: SimOptions) -> list[bool]:
    """Which job frames move the arm (its position or joints: what the virtual bench samples)."""
    from ..core.job import _moves_arm
    from ..core.motion import MotionModel, Planner
    from ..sim.model import _arm_profile

    model = MotionModel(_arm_profile(options), options.speed_factor)
    return [_moves_arm(segment) for segment in Planner(model).feed_all(commands)]


def abort_figures(stats: dict, written: int, stopped_s: float, lead_s: float, durations_s,
                  moves: list[bool]) -> tuple[float, float]:
    """(moving after the abort s, the stop bound s) on the arm's clock, for a stop asked at
    ``stopped_s`` on the host's (the same clock: ``time.monotonic``, or the port's virtual one)
    after ``written`` job frames: the frames that landed after them are the abort's."""
    from .table import stop_bound_s

    aborted_s = (stopped_s - stats["clock_start_s"]) * stats["time_scale"]
    log = [SimpleNamespace(index=index, start_s=start, end_s=end) for index, start, end, _ in stats["executions"]]
    arm = SimpleNamespace(execution_log=log)
    line = ["job"] * written + ["abort"] * (len(stats["frames"]) - written)
    # "The move in progress": the one the arm was in when the pause frame landed — a frame the host
    # counts begun (its line model) begins a little later at the arm, by the pty's own latency, so
    # at the instant of the stop it may not have begun yet there (the virtual bench has no latency)
    landed_s = min((arrival for index, arrival, _ in stats["frames"] if index >= written), default=aborted_s)
    moved_until = max((e.end_s for e in log if e.index < written and e.end_s is not None and moves[e.index]),
                      default=aborted_s)
    running = [e for e in log if e.index < written and e.end_s is None]
    if running:  # frozen by a pause that acted as it landed: it stopped when the pause landed
        moved_until = max(moved_until, min(arrival for index, arrival, _ in stats["frames"] if index >= written))
    return max(0.0, moved_until - aborted_s), stop_bound_s(arm, line, landed_s, list(durations_s), lead_s)


def run_row(name: str, commands, baud: int, lead_s: float = DEFAULT_LEAD_S) -> RealtimeRow:
    from .table import run_cell

    options = SimOptions(baud=baud)
    url = f"sim://?baud={baud}&{LINE_OPTIONS}"
    kind = _bound_kind(name, commands, options)
    target = LINE_BOUND_RATIO if kind == "line-bound" else ARM_BOUND_RATIO
    physical_s = physical_bound_s(commands, options)
    durations_s = true_durations_s(commands, options)
    half = len(commands) // 2  # the abort run stops after these (the virtual bench's moment)
    with tempfile.TemporaryDirectory(prefix="armctl-rt-") as folder:
        runs = {}
        for run in ("whole", "abort"):
            stats_path = os.path.join(folder, f"{run}.json")
            process, path = _start_sim(url, stats_path)
            try:
                stopped = drive(path, commands, baud, lead_s, half if run == "abort" else None)
            finally:
                stats = _stop_sim(process, stats_path)
            runs[run] = (stats, stopped)
    whole, _ = runs["whole"]
    mean_s, job_s, _ = _job_figures(whole, len(commands), baud)
    aborted, stopped = runs["abort"]
    moving_s, bound_s = (abort_figures(aborted, half, stopped, lead_s, durations_s, moving_frames(commands, options))
                         if stopped else (None, None))
    virtual = run_cell(Scenario(name, name, tuple(commands), options), "armctl", lead_s)
    virtual_ratio = virtual.job_s / physical_s
    row = RealtimeRow(baud, name, len(commands), kind, target, mean_s * 1000, frame_seconds(baud) * 1000, physical_s,
                      job_s, job_s / physical_s, virtual_ratio, whole["dropped"], aborted["dropped"], moving_s, bound_s,
                      virtual.moving_after_abort_s, "complete" if whole["complete"] else "records cut")
    _judge(row)
    return row


def _judge(row: RealtimeRow) -> None:
    failures = row.failures
    if row.dropped or row.abort_dropped:
        failures.append(f"{row.dropped} (+{row.abort_dropped}) frames dropped")
    if row.ratio > row.target:
        failures.append(f"{row.ratio:.3f} × the physical bound > {row.target:g}")
    if abs(row.ratio / row.virtual_ratio - 1) > AGREE_SHARE:
        failures.append(f"real time {row.ratio:.3f} vs virtual {row.virtual_ratio:.3f}: more than {AGREE_SHARE:.0%} apart")
    if row.moving_after_abort_s is None:
        failures.append("the abort run did not stop")
    elif row.moving_after_abort_s > row.stop_bound_s + frame_seconds(row.baud):
        failures.append(f"moved {row.moving_after_abort_s:.2f} s after the abort > {row.stop_bound_s:.2f} s")


HEADER = ("rate", "job", "frames", "kind", "inter-arrival ms", "÷ physical (target)", "virtual ÷ physical", "Δ",
          "dropped", "moving after abort s", "virtual moving s", "result")


def format_rows(rows: list[RealtimeRow]) -> str:
    table = [HEADER]
    for row in rows:
        moving = "-" if row.moving_after_abort_s is None else f"{row.moving_after_abort_s:.2f} (≤ {row.stop_bound_s:.2f})"
        table.append((
            str(row.baud), row.job, str(row.frames), row.bound_kind,
            f"{row.inter_arrival_ms:.2f} (line {row.frame_ms:.2f})", f"{row.ratio:.4f} (≤ {row.target:g})",
            f"{row.virtual_ratio:.4f}", f"{(row.ratio / row.virtual_ratio - 1) * 100:+.2f} %",
            f"{row.dropped} (+{row.abort_dropped})", moving,
            "-" if row.virtual_moving_after_abort_s is None else f"{row.virtual_moving_after_abort_s:.2f}",
            "met" if not row.failures else "MISSED: " + "; ".join(row.failures)))
    widths = [max(len(line[k]) for line in table) for k in range(len(HEADER))]
    lines = ["  ".join(cell.ljust(width) for cell, width in zip(line, widths)).rstrip() for line in table]
    lines.insert(1, "  ".join("-" * width for width in widths))
    return "\n".join(lines)


def main(lead_s: float = DEFAULT_LEAD_S, as_json: bool = False, rates=RATES) -> int:
    """Run the table, print it (or JSON); 1 when a target is missed."""
    from ..host.posix_terminal import require_posix_terminal

    require_posix_terminal("armctl bench --realtime", "run the virtual benchmark (armctl bench) instead")
    started = time.monotonic()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    rows = [run_row(name, commands, baud, lead_s) for baud in rates for name, commands in realtime_jobs()]
    wall_s = time.monotonic() - started
    missed = any(row.failures for row in rows)
    if as_json:
        print(json.dumps({"lead_s": lead_s, "wall_s": wall_s, "load_average": load,
                          "rows": [vars(row) for row in rows]}, indent=1))
    else:
        print(format_rows(rows))
        print(f"\n{len(rows)} rows in {wall_s:.0f} s of wall time; load average {load:.2f} at the start"
              if load is not None else f"\n{len(rows)} rows in {wall_s:.0f} s of wall time")
        print("every target met" if not missed else "MISSED targets (see the rows)")
    return 1 if missed else 0
