"""How fast, and in how much memory, armctl compiles a long motion script.

Generates (in a temporary directory) a script of N G1 lines with 6–8 words and comments, then
runs each contender on that same file in its own subprocess — so each peak RSS is its own —
and prints a table:

  armctl        armctl.script.compile_file(): parse, modal state, protocol command objects
  regex         a plain compiled-regex tokenizer (letter/number pairs per line): the floor
  gcodeparser   the PyPI package's streaming parser, gcodeparser.parse_gcode_lines()
                (GcodeParser, the class, is deprecated in 0.3 and builds the same objects
                into one list; --with-class adds it, at the cost of its memory)
  armctl-cli    the installed ``armctl compile FILE -o /dev/null``: read, check, encode and
                write every frame, timed as a whole process only

Targets (DESIGN): armctl's peak RSS <= 100 MB and armctl >= 0.5 x gcodeparser's lines/s in
process; issue 13: ``armctl compile`` >= 1.0 x gcodeparser as whole processes (each child's
CPU time from start to exit: interpreter, imports, parse — what a user waits for).
benchmarks/cli_speed.py prints that row with issue 13's other parse and lint rows.

This machine's speed drifts up to 2x within minutes, so a ratio of two best times taken
minutes apart moves with it (issue 13: 1.14 on one call, 0.49 on the next).  The contenders
run in --pairs rounds, back to back, the order alternating from round to round; the ratio
printed is the median of the per-round ratios, and each contender's lines/s the median of
its rounds.  Times are each child's CPU time (user + system) over the parse, which the other
processes on the machine disturb far less than wall time; for these single-threaded parsers
the two agree on an idle machine (the wall-clock seconds are printed too).

    .venv/bin/pip install -e '.[bench]'                        # gcodeparser, the reference
    .venv/bin/python benchmarks/compile_speed.py               # 1,000,000 lines, 5 pairs
    .venv/bin/python benchmarks/compile_speed.py --lines 100000 --pairs 9 --check
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import random
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MAX_RSS_MB = 100.0
MIN_RATIO = 0.5
MIN_WHOLE_RATIO = 1.0


# --- the script --------------------------------------------------------------------------------


def write_script(path: Path, lines: int, seed: int) -> None:
    """G1 lines with 6–8 words (X Y Z A B C, sometimes F and S) and ; or ( ) comments."""
    rng = random.Random(seed)
    with open(path, "w", encoding="utf-8") as out:
        out.write("G1 X0 Y0 Z100 A0 B0 C0 F3000 S1500 ; start from a known pose\n")
        for index in range(1, lines):
            words = [
                f"X{rng.uniform(-300, 300):.3f}", f"Y{rng.uniform(-300, 300):.3f}", f"Z{rng.uniform(0, 300):.2f}",
                f"A{rng.uniform(-90, 90):.1f}", f"B{rng.uniform(-90, 90):.1f}", f"C{rng.uniform(-180, 180):.1f}",
            ]
            extra = index % 3
            if extra >= 1:
                words.append(f"F{rng.choice((1200, 3000, 6000))}")
            if extra == 2:
                words.append(f"S{rng.randint(500, 2500)}")
            if index % 4 == 0:
                words.insert(3, "(attitude)")
            out.write("G1 " + " ".join(words) + f" ; point {index}\n")


# --- the contenders (each runs in a child process) ----------------------------------------------


def run_armctl(path: str) -> int:
    sys.path.insert(0, str(ROOT))
    from armctl.script import compile_file

    job = compile_file(path)
    count = sum(1 for _ in job)
    if job.error_count:
        raise SystemExit(f"armctl found {job.error_count} errors: {job.diagnostics[0]}")
    return count


def run_regex(path: str) -> int:
    import re

    word = re.compile(r"([A-Za-z])([-+]?[0-9]*\.?[0-9]+)")
    comment = re.compile(r"\([^)]*\)|;.*")
    count = 0
    with open(path, encoding="utf-8") as lines:
        for line in lines:
            words = [(letter.upper(), float(number)) for letter, number in word.findall(comment.sub("", line))]
            count += bool(words)
    return count


def run_gcodeparser(path: str) -> int:
    from gcodeparser import parse_gcode_lines

    with open(path, encoding="utf-8") as lines:
        return sum(1 for _ in parse_gcode_lines(lines))


def run_gcodeparser_class(path: str) -> int:
    import warnings

    from gcodeparser import GcodeParser

    warnings.simplefilter("ignore", DeprecationWarning)
    with open(path, encoding="utf-8") as source:
        return len(GcodeParser(source.read()).lines)


CONTENDERS = {
    "armctl": run_armctl,
    "regex": run_regex,
    "gcodeparser": run_gcodeparser,
    "gcodeparser-class": run_gcodeparser_class,
}


def peak_rss_mb() -> float:
    """This process's peak resident set size (VmHWM), in MB."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: kB


def child(name: str, path: str) -> None:
    start_rss = peak_rss_mb()
    start, start_cpu = time.perf_counter(), time.process_time()
    count = CONTENDERS[name](path)
    seconds, cpu_seconds = time.perf_counter() - start, time.process_time() - start_cpu
    print(json.dumps({"name": name, "count": count, "seconds": seconds, "cpu_seconds": cpu_seconds,
                      "peak_rss_mb": peak_rss_mb(), "start_rss_mb": start_rss}))


def armctl_command() -> list[str]:
    """The installed console script next to this interpreter, else ``python -m armctl``."""
    script = Path(sys.executable).with_name("armctl")
    return [str(script)] if script.exists() else [sys.executable, "-m", "armctl"]


def measure(name: str, path: Path) -> dict:
    """One contender's run; ``process_cpu_seconds`` is its whole process (see the docstring)."""
    if name == "armctl-cli":
        command = [*armctl_command(), "compile", str(path), "-o", os.devnull]
    else:
        command = [sys.executable, __file__, "--child", name, str(path)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    result = subprocess.run(command, capture_output=True, text=True, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if result.returncode != 0:
        raise SystemExit(f"{name} failed:\n{result.stderr}")
    process_cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    found = {} if name == "armctl-cli" else json.loads(result.stdout.splitlines()[-1])
    return {**found, "process_cpu_seconds": process_cpu}


# --- the table ---------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lines", type=int, default=1_000_000, help="script length (default 1,000,000)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--pairs", "--repeat", type=int, default=5,
                        help="rounds of alternating runs; ratios are medians of per-round ratios (default 5)")
    parser.add_argument("--with-class", action="store_true", help="also measure gcodeparser.GcodeParser (whole file)")
    parser.add_argument("--check", action="store_true", help="exit 1 if armctl misses a target")
    parser.add_argument("--child", nargs=2, metavar=("NAME", "PATH"), help=argparse.SUPPRESS)
    options = parser.parse_args(argv)
    if options.child:
        child(*options.child)
        return 0

    if importlib.util.find_spec("gcodeparser") is None:
        # the reference contender: without it there is no target to compare against
        print("compile_speed: the package gcodeparser is not installed; install the bench extra "
              "first: pip install -e '.[bench]'", file=sys.stderr)
        return 2
    names = ["armctl", "gcodeparser", "regex"] + (["gcodeparser-class"] if options.with_class else [])
    names_run = ["armctl-cli", *names]  # armctl-cli next to gcodeparser when the order turns round
    with tempfile.TemporaryDirectory(prefix="armctl-bench-") as folder:
        path = Path(folder) / "job.txt"
        write_script(path, options.lines, options.seed)
        size_mb = path.stat().st_size / 1e6
        print(f"script: {options.lines:,} lines, {size_mb:.1f} MB ({sys.implementation.name} {sys.version.split()[0]})")
        rounds = []  # one {name: run} per round
        for index in range(max(options.pairs, 1)):  # back to back, so load on the machine hits all alike
            order = names_run if index % 2 == 0 else names_run[::-1]  # armctl and gcodeparser adjacent either way
            rounds.append({name: measure(name, path) for name in order})

    print(f"{'contender':<18} {'lines/s':>12} {'CPU s':>9} {'wall s':>9} {'peak RSS MB':>12} {'at start MB':>12}"
          f"   (medians of {len(rounds)} rounds)")
    for name in names:
        runs = [r[name] for r in rounds]
        median_cpu = statistics.median(run["cpu_seconds"] for run in runs)
        median_s = statistics.median(run["seconds"] for run in runs)
        peak = max(run["peak_rss_mb"] for run in runs)
        start = statistics.median(run["start_rss_mb"] for run in runs)
        print(f"{name:<18} {options.lines / median_cpu:>12,.0f} {median_cpu:>9.2f} {median_s:>9.2f} {peak:>12.1f}"
              f" {start:>12.1f}")
    ratios = [r["gcodeparser"]["cpu_seconds"] / r["armctl"]["cpu_seconds"] for r in rounds]
    ratio = statistics.median(ratios)
    rss = max(r["armctl"]["peak_rss_mb"] for r in rounds)
    print(f"per-round armctl / gcodeparser: {', '.join(f'{value:.2f}' for value in ratios)}")
    speed_ok, memory_ok = ratio >= MIN_RATIO, rss <= MAX_RSS_MB
    print(f"armctl / gcodeparser lines/s: {ratio:.2f}, median of per-round ratios (target >= {MIN_RATIO})"
          f" {'ok' if speed_ok else 'MISSED'}")
    print(f"armctl peak RSS: {rss:.1f} MB, the highest round (target <= {MAX_RSS_MB:.0f} MB) {'ok' if memory_ok else 'MISSED'}")
    whole = [r["gcodeparser"]["process_cpu_seconds"] / r["armctl-cli"]["process_cpu_seconds"] for r in rounds]
    whole_ratio = statistics.median(whole)
    print(f"armctl compile / gcodeparser lines/s, whole processes: {whole_ratio:.2f}, median of per-round ratios "
          f"{', '.join(f'{value:.2f}' for value in whole)} (issue 13's target >= {MIN_WHOLE_RATIO}) "
          f"{'ok' if whole_ratio >= MIN_WHOLE_RATIO else 'MISSED'}")
    print(f"reproduce: .venv/bin/python benchmarks/compile_speed.py --lines {options.lines} --pairs {options.pairs}"
          f" --seed {options.seed}")
    return 1 if options.check and not (speed_ok and memory_ok) else 0


if __name__ == "__main__":
    sys.exit(main())
