"""Issue 13's lint and start-up rows, measured side by side in one run: whole processes, the
installed ``armctl`` command, medians of alternating pairs.

  lint lines/s     ``armctl lint plain.txt``: N plain ``G1 X Y Z`` lines (a random walk of
                   steps up to 25 mm inside the reachable part of the workspace, so every rule
                   and the E012 motion clock run on every line), lines ÷ the whole process's
                   CPU time; target >= 50,000 lines/s.  Each run is paired with the bare
                   imports below, so the figure also reads as a ratio that survives load.
  start-up ratio   ``armctl lint small.txt`` (20 lines, two with a parameter, so the Lark
                   parser is loaded) ÷ ``python -c 'import click, lark, rich'``; target <= 1.5.

This machine's speed drifts up to 2x within minutes, so each row is the median of per-pair
ratios of runs taken back to back in alternating order; only ratios from one run count.  A
run's time is the CPU time (user + system) of its process, which the other processes on the
machine disturb far less than wall time; for these single-threaded processes the two agree
on an idle machine.
Children run with bytecode writing allowed (PYTHONDONTWRITEBYTECODE unset: an installed wheel
has its .pyc files) and with a private, pre-warmed XDG_CACHE_HOME (the Lark tables' cache,
armctl/script/grammar.py), after one warm-up run of each command.

    .venv/bin/python benchmarks/cli_speed.py                        # 100,000 lines, 15 pairs
    .venv/bin/python benchmarks/cli_speed.py --lines 20000 --pairs 9 --check
"""

from __future__ import annotations

import argparse
import os
import random
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

LINT_TARGET_LINES_S = 50_000.0
STARTUP_TARGET_RATIO = 1.5
BARE_IMPORTS = "import click, lark, rich"


def write_plain(path: Path, lines: int, seed: int) -> None:
    """A random walk of plain G1 X Y Z lines, tool down, inside the arm's reach."""
    rng = random.Random(seed)
    x, y, z = 220.0, 0.0, 150.0
    with open(path, "w", encoding="utf-8") as out:
        out.write("G1 X220 Y0 Z150 A180 B0 C0 F6000 S1000\n")
        for _ in range(1, lines):
            x = min(max(x + rng.uniform(-25, 25), 150.0), 300.0)
            y = min(max(y + rng.uniform(-25, 25), -150.0), 150.0)
            z = min(max(z + rng.uniform(-25, 25), 40.0), 280.0)
            out.write(f"G1 X{x:.2f} Y{y:.2f} Z{z:.2f}\n")


def write_small(path: Path) -> None:
    """20 lines, as a short hand-written job: two use a parameter (the Lark parser), 18 are plain."""
    lines = ["#<z> = 150", "G1 X[200 + 20] Y0 Z#<z> A180 B0 C0 F3000 S1000"]
    lines += [f"G1 X{200 + 5 * k} Y{-40 + 4 * k} Z{150 - 3 * k}" for k in range(18)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def armctl_command() -> list[str]:
    """The installed console script next to this interpreter, else ``python -m armctl``."""
    script = Path(sys.executable).with_name("armctl")
    return [str(script)] if script.exists() else [sys.executable, "-m", "armctl"]


def seconds(command: list[str], env: dict, cwd: Path) -> float:
    """The CPU time (user + system) of one run of ``command``: see the module docstring."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, cwd=cwd, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    elapsed = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if done.returncode not in (0, 1):  # 1: lint found problems, still a full run
        raise SystemExit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr.decode(errors='replace')}")
    return elapsed


def pairs(first: list[str], second: list[str], count: int, env: dict, cwd: Path) -> list[tuple[float, float]]:
    """``count`` (first, second) wall times, the order alternating from pair to pair."""
    found = []
    for index in range(count):
        if index % 2 == 0:
            a = seconds(first, env, cwd)
            b = seconds(second, env, cwd)
        else:
            b = seconds(second, env, cwd)
            a = seconds(first, env, cwd)
        found.append((a, b))
    return found


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lines", type=int, default=100_000, help="plain lines to lint (default 100,000)")
    parser.add_argument("--pairs", type=int, default=15, help="alternating pairs per row (default 15)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--check", action="store_true", help="exit 1 if a row misses its target")
    options = parser.parse_args(argv)
    armctl = armctl_command()
    bare = [sys.executable, "-c", BARE_IMPORTS]
    with tempfile.TemporaryDirectory(prefix="armctl-cli-speed-") as folder:
        work = Path(folder)
        env = {key: value for key, value in os.environ.items() if key != "PYTHONDONTWRITEBYTECODE"}
        env["XDG_CACHE_HOME"] = str(work / "cache")
        plain, small = work / "plain.txt", work / "small.txt"
        write_plain(plain, options.lines, options.seed)
        write_small(small)
        lint_plain, lint_small = [*armctl, "lint", plain.name], [*armctl, "lint", small.name]
        for command in (lint_small, bare, lint_plain):  # warm-up: bytecode, the Lark cache, the page cache
            seconds(command, env, work)
        start_up = pairs(lint_small, bare, options.pairs, env, work)
        lint = pairs(lint_plain, bare, max(options.pairs // 3, 3), env, work)

    startup_ratio = statistics.median(a / b for a, b in start_up)
    rates = [options.lines / a for a, _ in lint]
    lines_s = statistics.median(rates)
    lint_over_bare = statistics.median(a / b for a, b in lint)
    bare_ms = statistics.median(b for _, b in start_up) * 1e3
    small_ms = statistics.median(a for a, _ in start_up) * 1e3
    lint_ok, startup_ok = lines_s >= LINT_TARGET_LINES_S, startup_ratio <= STARTUP_TARGET_RATIO
    print(f"{sys.implementation.name} {sys.version.split()[0]}; {' '.join(armctl)}")
    print(f"{'row':<44} {'measured':>12} {'target':>10}")
    print(f"{'armctl lint of plain lines, lines/s':<44} {lines_s:>12,.0f} {'>= 50,000':>10} "
          f"{'ok' if lint_ok else 'MISSED'}  (median of {len(rates)}; min {min(rates):,.0f}, max {max(rates):,.0f};"
          f" {options.lines:,} lines = {lint_over_bare:.1f}x the bare imports)")
    print(f"{'armctl lint small.txt / bare imports':<44} {startup_ratio:>12.2f} {'<= 1.5':>10} "
          f"{'ok' if startup_ok else 'MISSED'}  (median of {len(start_up)} pairs; {small_ms:.0f} ms vs {bare_ms:.0f} ms)")
    print("reproduce: .venv/bin/python benchmarks/cli_speed.py "
          f"--lines {options.lines} --pairs {options.pairs} --seed {options.seed}")
    return 1 if options.check and not (lint_ok and startup_ok) else 0


if __name__ == "__main__":
    sys.exit(main())
