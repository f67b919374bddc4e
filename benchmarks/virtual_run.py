"""Issue 11's virtual-time row: the wall time of a 20-minute job on ``sim://?clock=virtual``,
and its ratio to the bare simulator doing the same 20 minutes with no host.

  run        ``armctl run JOB --port sim://?clock=virtual`` in this process (ui/run_job.run_job:
             lint, read the arm, estimate, stream through the job engine, wait for the end),
             JOB = 12 moves of 100 mm at F60 (about 1,200 s of arm time, 40,000 status frames);
             target <= 0.5 s of wall time.
  baseline   the same simulated arm, fed the same frames at the same model times (recorded
             from the run), advanced to the run's last model time as the run's link drives it —
             its quiet stretches as runs of status frames timed ahead (``status_run``), each
             frame built and decoded, the other steps burst by burst — with no engine: what any
             host pays at least.  The ratio run ÷ baseline is the host's and the engine's own
             cost, and survives load.

This machine's speed drifts within minutes, so the figures are medians of pairs taken back to
back in alternating order; only a ratio from one run counts.  The CPU time of each (this
process's, ``time.process_time``) is printed too: other processes on the machine disturb it far
less than the wall time.

    .venv/bin/python benchmarks/virtual_run.py             # 5 pairs
    .venv/bin/python benchmarks/virtual_run.py --pairs 9

Issue 23's measure (``--cost``): the CPU of a 24,000-frame ``armctl -q run JOB --port
'sim://?clock=virtual' --no-live`` (JOB: 12,000 passes of two 1 mm moves at F3000, about 1,400 s of
arm time) — the installed command in a fresh process, its CPU from the child's rusage (user +
system) — against the bare simulator replaying the same frames (``baseline``, target at most
1.5×) and against ``armctl compile JOB`` in a fresh process (target at most 10×).  Each
figure is the median of ``--pairs`` runs, taken in alternating order.  It prints the floor too:
the bare simulator plus ``armctl estimate JOB`` (start-up, reading, checking and planning the
script, which a run does once before its first frame) — no host can stream the job for less —
and what is left for the streaming itself within both targets.

    .venv/bin/python benchmarks/virtual_run.py --cost --pairs 3

``--split`` says where the run's CPU goes, in this process: the same 24,000-frame job with a
counter around the job engine's three entry points (``Job.receive_statuses``, ``next_action``,
``wrote``) and the simulated port's (``advance_to``, ``virtual_status_run``, ``status_frames``,
``write``); the rest is the host's edge (the driver, the virtual waits, the link, the runner,
reading and checking the script).  The counters cost a little themselves (timed, and printed).
What it answers: the run's CPU less its engine's, against the bare simulator — the ratio the
run would reach if the engine cost nothing.

    .venv/bin/python benchmarks/virtual_run.py --split
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

URL = "sim://?clock=virtual"
TARGET_WALL_S = 0.5
MOVES = 12
FEED_MM_MIN = 60.0
LENGTH_MM = 100.0


def write_job(path: Path) -> None:
    lines = ["G90", "G1 X250 Y-50 Z150 A180 B0 C0 F3000 S1000"]
    lines += [f"G1 Y{50 if k % 2 == 0 else -50} F{FEED_MM_MIN:g}" for k in range(MOVES)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def one_run(script_path: Path) -> tuple[tuple[float, float], list[tuple[float, bytes]], float, str]:
    """(wall, CPU) seconds of ``armctl run`` in this process; the frames written with their
    model times; the last model time; the summary printed."""
    from armctl.ui.cli import _read_script
    from armctl.host.link import connect as real_connect
    from armctl.ui.run_job import JobOptions, run_job

    written: list[tuple[float, bytes]] = []
    links = []

    def connect(port, baud, profile=None):
        link, baud = real_connect(port, baud, announce=lambda text: None, profile=profile)
        write, clock = link.write, link.clock

        def recording(frame: bytes) -> None:
            written.append((clock.now(), frame))
            write(frame)

        link.write = recording
        links.append(link)
        return link, baud

    options = JobOptions(str(script_path), URL, None, 2.0, 1, False, None, False, "pause", None, 3.0)
    snapshot = _read_script(str(script_path))
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        start, cpu_start = time.perf_counter(), time.process_time()
        code = run_job(options, snapshot, connect)
        wall_s, cpu_s = time.perf_counter() - start, time.process_time() - cpu_start
    if code != 0:
        raise SystemExit(f"the run failed (exit {code}):\n{out.getvalue()}")
    return (wall_s, cpu_s), written, links[0].clock.now(), out.getvalue()


def baseline(written: list[tuple[float, bytes]], end_s: float) -> tuple[float, float]:
    """(wall, CPU) seconds of the bare simulator replaying ``written`` and advancing to ``end_s``
    the way the run's link drives it: its quiet stretches as runs of steps timed ahead, each
    frame built and decoded (``status_run``, ``status_frames``, ``StatusReader.decode_frame``),
    every other step burst by burst (``advance``, ``StatusReader.feed``)."""
    from armctl.core.protocol import StatusReader
    from armctl.sim.model import SimulatedArm
    from armctl.sim.protocol_sim import parse_sim_url

    options = parse_sim_url(URL)
    arm, reader = SimulatedArm(options), StatusReader()
    writes = list(written)
    start, cpu_start = time.perf_counter(), time.process_time()
    now, k, frames = 0.0, 0, 0
    while now < end_s:
        until_s = min(writes[k][0], end_s) if k < len(writes) else end_s
        run = arm.status_run(now, until_s, 1e-6, 512, 0.0, 1.0)
        if run:
            for data in arm.status_frames(run):
                frames += reader.decode_frame(data) is not None
            arm.commit_status_run(run, len(run))
            now = run[-1][0]
            continue
        due_s = min(arm.next_output_time(), end_s)
        while k < len(writes) and writes[k][0] <= due_s:
            arm.write(writes[k][1], writes[k][0])
            k += 1
        now = due_s
        frames += len(reader.feed(arm.advance(now)))
    return time.perf_counter() - start, time.process_time() - cpu_start


COST_PASSES = 12_000  # two frames a pass, plus the first move: 24,001 frames
COST_TARGET_SIMULATOR = 1.5  # run CPU / the bare simulator's CPU on the same frames
COST_TARGET_COMPILE = 10.0  # run CPU / `armctl compile` CPU of the same script
ARMCTL = Path(sys.executable).with_name("armctl")  # the installed command, next to this interpreter


def write_cost_job(path: Path) -> None:
    """Issue 23's 24,000-frame job (as /work/perf24k.sh writes it)."""
    path.write_text(f"G90\nG1 X250 Y-50 Z150 A180 B0 C0 F3000 S1000\nO<a> repeat [{COST_PASSES}]\n"
                    "G1 Y-49 F3000\nG1 Y-50\nO<a> endrepeat\n", encoding="utf-8")


def child_cpu_s(*words: str) -> float:
    """User + system CPU seconds of ``armctl WORDS`` in a fresh process (its own rusage); its
    output is discarded, a failure stops the benchmark."""
    with tempfile.TemporaryFile() as errors:  # a file, not a pipe: a chatty child cannot block on it
        process = subprocess.Popen([str(ARMCTL), *words], stdout=subprocess.DEVNULL, stderr=errors)
        _, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        if process.returncode != 0:
            errors.seek(0)
            raise SystemExit(f"armctl {' '.join(words)} failed (exit {process.returncode}): "
                             f"{errors.read().decode(errors='replace')}")
    return usage.ru_utime + usage.ru_stime


def cost(pairs: int) -> int:
    """Issue 23's measure (see the module docstring); exit 1 when a target is missed."""
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "job24k.txt"
        write_cost_job(script)
        _, written, end_s, _ = one_run(script)  # the frames to replay (the same every run)
        run_words = ("-q", "run", str(script), "--port", URL, "--no-live")
        runs, bases, compiles, estimates = [], [], [], []
        for pair in range(pairs):
            steps = [lambda: runs.append(child_cpu_s(*run_words)), lambda: bases.append(baseline(written, end_s)[1]),
                     lambda: compiles.append(child_cpu_s("compile", str(script))),
                     lambda: estimates.append(child_cpu_s("estimate", str(script)))]
            for step in steps if pair % 2 == 0 else reversed(steps):
                step()
    run_s, base_s, compile_s, estimate_s = (statistics.median(values) for values in (runs, bases, compiles, estimates))
    print(f"job: {len(written)} frames, model time simulated {end_s:.1f} s")
    print(f"armctl -q run (fresh process) CPU median {run_s:.2f} s, runs {', '.join(f'{r:.2f}' for r in runs)}")
    print(f"bare simulator (same frames) CPU median {base_s:.2f} s; ratio {run_s / base_s:.2f} (target <= {COST_TARGET_SIMULATOR:g})")
    print(f"armctl compile (fresh process) CPU median {compile_s:.2f} s; ratio {run_s / compile_s:.1f} "
          f"(target <= {COST_TARGET_COMPILE:g})")
    # The floor no streaming host can go under: the simulator's own work plus what a run does once
    # before its first frame (start-up, reading, checking and planning the script: `armctl estimate`)
    floor_s = base_s + estimate_s
    print(f"floor: bare simulator + armctl estimate (fresh process, CPU median {estimate_s:.2f} s) = {floor_s:.2f} s, "
          f"{floor_s / compile_s:.1f}x compile; what streaming may cost within both targets: "
          f"{min(COST_TARGET_SIMULATOR * base_s, COST_TARGET_COMPILE * compile_s) - floor_s:+.2f} s "
          f"(it costs {run_s - floor_s:.2f} s)")
    met = run_s / base_s <= COST_TARGET_SIMULATOR and run_s / compile_s <= COST_TARGET_COMPILE
    print("targets met" if met else "targets missed")
    return 0 if met else 1


SPLIT_ENGINE = ("armctl.core.job", "Job", ("receive_statuses", "next_action", "wrote"))
SPLIT_SIMULATOR = ("armctl.sim.protocol_sim", "Serial", ("advance_to", "virtual_status_run", "status_frames", "write"))


def _counted(spent: dict, part: str, function):
    """``function`` with its CPU added to ``spent[part]`` (outermost calls only: none of these
    calls another, but a counted call inside a counted call must not count twice)."""
    clock = time.process_time

    def counted(*args, **kwargs):
        if spent["depth"]:
            return function(*args, **kwargs)
        spent["depth"] = 1
        start = clock()
        try:
            return function(*args, **kwargs)
        finally:
            spent[part] += clock() - start
            spent["calls"] += 1
            spent["depth"] = 0
    return counted


@contextlib.contextmanager
def _counters(spent: dict):
    """The engine's and the simulated port's entry points counted into ``spent`` meanwhile."""
    import importlib
    originals = []
    try:
        for part, (module, name, methods) in (("engine", SPLIT_ENGINE), ("simulator", SPLIT_SIMULATOR)):
            owner = getattr(importlib.import_module(module), name)
            for method in methods:
                originals.append((owner, method, owner.__dict__[method]))
                setattr(owner, method, _counted(spent, part, owner.__dict__[method]))
        yield
    finally:
        for owner, method, function in originals:
            setattr(owner, method, function)


def split(pairs: int) -> tuple[float, float, float, float]:
    """``--split`` (see the module docstring): prints the split; returns the medians (run, engine,
    simulated port, bare simulator) in CPU seconds."""
    spent = {"engine": 0.0, "simulator": 0.0, "calls": 0, "depth": 0}
    # what one counter costs: a counted call of a function that does nothing
    probe = {"nothing": 0.0, "calls": 0, "depth": 0}
    nothing = _counted(probe, "nothing", lambda: None)
    start = time.process_time()
    for _ in range(100_000):
        nothing()
    per_call_s = (time.process_time() - start) / 100_000
    rows = []
    with tempfile.TemporaryDirectory() as tmp, _counters(spent):
        script = Path(tmp) / "job24k.txt"
        write_cost_job(script)
        one_run(script)  # warm-up: imports, the grammar cache
        for _ in range(pairs):
            spent.update(engine=0.0, simulator=0.0, calls=0)
            (_, run_s), written, end_s, _ = one_run(script)
            counters_s = spent["calls"] * per_call_s
            rows.append((run_s, spent["engine"], spent["simulator"], counters_s, baseline(written, end_s)[1]))
    run_s, engine_s, simulator_s, counters_s, base_s = (statistics.median(column) for column in zip(*rows))
    edge_s = run_s - engine_s - simulator_s - counters_s
    print(f"job: {len(written)} frames, model time simulated {end_s:.1f} s; medians of {pairs} in-process runs")
    print(f"run CPU {run_s:.2f} s = job engine {engine_s:.2f} s + simulated port {simulator_s:.2f} s "
          f"+ host edge {edge_s:.2f} s + counters about {counters_s:.2f} s ({spent['calls']} calls)")
    print(f"bare simulator (same frames) CPU {base_s:.2f} s; run / bare {run_s / base_s:.2f}; "
          f"without the engine's share {(run_s - engine_s - counters_s) / base_s:.2f}; "
          f"the edge's share alone {edge_s / base_s:.2f} of the bare simulator")
    return run_s, engine_s, simulator_s, base_s


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=5)
    parser.add_argument("--cost", action="store_true", help="issue 23's measure: a 24,000-frame run against the "
                        "bare simulator and against armctl compile, each in a fresh process")
    parser.add_argument("--split", action="store_true", help="where the 24,000-frame run's CPU goes: the job "
                        "engine, the simulated port and the host's edge (in this process)")
    args = parser.parse_args()
    if args.split:
        split(args.pairs)
        return 0
    if args.cost:
        return cost(args.pairs)
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "twenty_minutes.txt"
        write_job(script)
        one_run(script)  # warm-up: imports, the grammar cache
        runs, bases = [], []
        _, written, end_s, summary = one_run(script)  # the frames to replay (the same every run)
        for pair in range(args.pairs):
            if pair % 2 == 0:
                runs.append(one_run(script)[0])
                bases.append(baseline(written, end_s))
            else:
                bases.append(baseline(written, end_s))
                runs.append(one_run(script)[0])
    arm_time = next((line for line in summary.splitlines() if line.startswith("arm time:")), "arm time: ?")
    print(f"job: {MOVES} moves of {LENGTH_MM:g} mm at F{FEED_MM_MIN:g}, {arm_time}")
    print(f"model time simulated: {end_s:.1f} s")
    for k, what in enumerate(("wall", "CPU")):
        run_s, base_s = [r[k] for r in runs], [b[k] for b in bases]
        ratio = statistics.median(r / b for r, b in zip(run_s, base_s))
        target = f" (target <= {TARGET_WALL_S} s)" if what == "wall" else ""
        print(f"{what:>4}: run median {statistics.median(run_s):.3f} s{target}, runs {', '.join(f'{r:.3f}' for r in run_s)}; "
              f"baseline (the bare simulator, same frames) median {statistics.median(base_s):.3f} s; "
              f"ratio run / baseline median {ratio:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
