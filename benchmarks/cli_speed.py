"""Issue 13's parse and lint rows, measured side by side in one run: whole processes, the
installed ``armctl`` command, medians of alternating pairs.

  compile ÷ gcodeparser  ``armctl compile plain.txt -o /dev/null`` (N lines of G1 with 6–8
                   words and comments, benchmarks/compile_speed.py's script: parse, check,
                   encode every frame, write its hex) against a process that imports
                   gcodeparser and parses the same file with ``parse_gcode_lines``:
                   gcodeparser's CPU time ÷ armctl's, i.e. armctl's lines/s as a multiple of
                   gcodeparser's; target >= 1.0.
  expression lines/s  ``armctl compile expr.txt -o /dev/null`` and ``armctl lint expr.txt``
                   on N lines that are all parameters and expressions (``#<x> = [#<x> + 1.5]``,
                   ``G1 X[#<x> + 0.5] Y#<y> Z[#<z> - 0.5]``, a random walk inside the reach):
                   lines ÷ the whole process's CPU time; target >= 25,000 lines/s each.
  lint lines/s     ``armctl lint walk.txt``: N plain ``G1 X Y Z`` lines (a random walk of
                   steps up to 25 mm inside the reachable part of the workspace, so every rule
                   and the E012 motion clock run on every line), lines ÷ the whole process's
                   CPU time; target >= 50,000 lines/s.
  start-up ratio   ``armctl lint small.txt`` (20 lines, two with a parameter) ÷
                   ``python -c 'import click, lark, rich'``; target <= 1.5.

Each rate's run is paired with the bare imports, so it also reads as a ratio that survives
load.  This machine's speed drifts up to 2x within minutes, so each row is the median of
per-pair ratios (or rates) of runs taken back to back in alternating order; only figures
from one run count.  A run's time is the CPU time (user + system) of its process, which the
other processes on the machine disturb far less than wall time; for these single-threaded
processes the two agree on an idle machine.
Children run with bytecode writing allowed (PYTHONDONTWRITEBYTECODE unset: an installed wheel
has its .pyc files) and with a private, pre-warmed XDG_CACHE_HOME (the Lark tables' cache,
armctl/script/grammar.py), after one warm-up run of each command.

    .venv/bin/pip install -e '.[bench]'                             # gcodeparser, the reference
    .venv/bin/python benchmarks/cli_speed.py                        # the issue's sizes
    .venv/bin/python benchmarks/cli_speed.py --lines 20000 --pairs 9 --check
    .venv/bin/python benchmarks/cli_speed.py --keep /tmp/speed     # keep the scripts: rerun a row by hand
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import shlex
import os
import random
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import compile_speed  # noqa: E402 - the compile row's script

LINT_TARGET_LINES_S = 50_000.0
EXPRESSION_TARGET_LINES_S = 25_000.0
COMPILE_TARGET_RATIO = 1.0
STARTUP_TARGET_RATIO = 1.5
BARE_IMPORTS = "import click, lark, rich"
# gcodeparser's whole process: import it, parse the file line by line (its streaming parser)
GCODEPARSER = ("import sys; from gcodeparser import parse_gcode_lines; lines = open(sys.argv[1], encoding='utf-8'); "
               "sys.exit(0 if sum(1 for _ in parse_gcode_lines(lines)) else 1)")


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


def write_expressions(path: Path, lines: int, seed: int) -> None:
    """Parameters and expressions only: each step assigns the next point of a random walk
    (inside the reach, as ``write_plain``) and moves there through expressions."""
    rng = random.Random(seed)
    point = {"x": 220.0, "y": 0.0, "z": 150.0}
    bounds = {"x": (150.0, 300.0), "y": (-150.0, 150.0), "z": (40.0, 280.0)}
    with open(path, "w", encoding="utf-8") as out:
        out.write("#<x> = 220\n#<y> = 0\n#<z> = 150\nG1 X#<x> Y#<y> Z#<z> A180 B0 C0 F6000 S1000\n")
        written = 4
        while written < lines:
            name = "xyz"[written % 3]
            low, high = bounds[name]
            step = round(min(max(point[name] + rng.uniform(-20, 20), low + 1), high - 1) - point[name], 2)
            point[name] += step
            out.write(f"#<{name}> = [#<{name}> + {step}]\n")
            out.write(f"G1 X[#<x> + 0.5] Y#<y> Z[#<z> - 0.5] (step {written})\n")
            written += 2


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
    """``count`` (first, second) CPU times, the order alternating from pair to pair."""
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
    parser.add_argument("--compile-lines", type=int, default=200_000,
                        help="lines for armctl compile vs gcodeparser (default 200,000)")
    parser.add_argument("--expression-lines", type=int, default=50_000,
                        help="parameter and expression lines to compile and lint (default 50,000)")
    parser.add_argument("--pairs", type=int, default=15, help="alternating pairs of the start-up row (default 15; "
                        "the other rows take a third as many, at least 3)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--check", action="store_true", help="exit 1 if a row misses its target")
    parser.add_argument("--keep", metavar="DIR", help="write the generated scripts into DIR and keep them, so each "
                        "row's commands (printed below the table) can be run again by hand; default: a temporary folder")
    options = parser.parse_args(argv)
    if importlib.util.find_spec("gcodeparser") is None:
        print("cli_speed: the package gcodeparser is not installed; install the bench extra "
              "first: pip install -e '.[bench]'", file=sys.stderr)
        return 2
    armctl = armctl_command()
    bare = [sys.executable, "-c", BARE_IMPORTS]
    few = max(options.pairs // 3, 3)
    with (contextlib.nullcontext(options.keep) if options.keep else tempfile.TemporaryDirectory(prefix="armctl-cli-speed-")) as folder:
        work = Path(folder)
        work.mkdir(parents=True, exist_ok=True)
        env = {key: value for key, value in os.environ.items() if key != "PYTHONDONTWRITEBYTECODE"}
        env["XDG_CACHE_HOME"] = str(work / "cache")
        walk, small, plain, expressions = work / "walk.txt", work / "small.txt", work / "plain.txt", work / "expr.txt"
        write_plain(walk, options.lines, options.seed)
        write_small(small)
        compile_speed.write_script(plain, options.compile_lines, options.seed)
        write_expressions(expressions, options.expression_lines, options.seed)
        lint_walk, lint_small = [*armctl, "lint", walk.name], [*armctl, "lint", small.name]
        compile_plain = [*armctl, "compile", plain.name, "-o", os.devnull]
        gcodeparser = [sys.executable, "-c", GCODEPARSER, plain.name]
        compile_expressions = [*armctl, "compile", expressions.name, "-o", os.devnull]
        lint_expressions = [*armctl, "lint", expressions.name]
        for command in (lint_small, bare, lint_walk, compile_plain, gcodeparser, compile_expressions, lint_expressions):
            seconds(command, env, work)  # warm-up: bytecode, the Lark cache, the page cache
        start_up = pairs(lint_small, bare, options.pairs, env, work)
        versus = pairs(compile_plain, gcodeparser, few, env, work)
        compiled = pairs(compile_expressions, bare, few, env, work)
        linted = pairs(lint_expressions, bare, few, env, work)
        lint = pairs(lint_walk, bare, few, env, work)

    def rate(found: list, lines: int) -> tuple[float, list[float]]:
        rates = [lines / a for a, _ in found]
        return statistics.median(rates), rates

    compile_ratio = statistics.median(b / a for a, b in versus)
    compile_ratios = [b / a for a, b in versus]
    compile_s, expression_rates = rate(compiled, options.expression_lines)
    lint_expression_s, lint_expression_rates = rate(linted, options.expression_lines)
    lines_s, rates = rate(lint, options.lines)
    lint_over_bare = statistics.median(a / b for a, b in lint)
    startup_ratio = statistics.median(a / b for a, b in start_up)
    bare_ms = statistics.median(b for _, b in start_up) * 1e3
    small_ms = statistics.median(a for a, _ in start_up) * 1e3
    rows = [
        (f"armctl compile / gcodeparser, {options.compile_lines:,} lines", f"{compile_ratio:.2f}", ">= 1.0",
         compile_ratio >= COMPILE_TARGET_RATIO,
         f"median of {len(versus)} pairs: {', '.join(f'{r:.2f}' for r in compile_ratios)}; whole processes, CPU "
         f"{statistics.median(a for a, _ in versus):.2f} s vs {statistics.median(b for _, b in versus):.2f} s"),
        ("armctl compile of expression lines, lines/s", f"{compile_s:,.0f}", ">= 25,000",
         compile_s >= EXPRESSION_TARGET_LINES_S,
         f"median of {len(compiled)}; min {min(expression_rates):,.0f}, max {max(expression_rates):,.0f}; "
         f"{options.expression_lines:,} lines"),
        ("armctl lint of expression lines, lines/s", f"{lint_expression_s:,.0f}", ">= 25,000",
         lint_expression_s >= EXPRESSION_TARGET_LINES_S,
         f"median of {len(linted)}; min {min(lint_expression_rates):,.0f}, max {max(lint_expression_rates):,.0f}"),
        ("armctl lint of plain lines, lines/s", f"{lines_s:,.0f}", ">= 50,000", lines_s >= LINT_TARGET_LINES_S,
         f"median of {len(rates)}; min {min(rates):,.0f}, max {max(rates):,.0f}; {options.lines:,} lines = "
         f"{lint_over_bare:.1f}x the bare imports"),
        ("armctl lint small.txt / bare imports", f"{startup_ratio:.2f}", "<= 1.5", startup_ratio <= STARTUP_TARGET_RATIO,
         f"median of {len(start_up)} pairs; {small_ms:.0f} ms vs {bare_ms:.0f} ms"),
    ]
    print(f"{sys.implementation.name} {sys.version.split()[0]}; {' '.join(armctl)}")
    print(f"{'row':<46} {'measured':>10} {'target':>10}")
    for name, measured, target, ok, detail in rows:
        print(f"{name:<46} {measured:>10} {target:>10} {'ok' if ok else 'MISSED'}  ({detail})")
    shown = lambda command: shlex.join(["python" if part == sys.executable else part for part in command])  # noqa: E731
    print(f"commands (in {options.keep or 'a temporary folder'}, with XDG_CACHE_HOME=cache there and bytecode "
          f"writing allowed; python is {sys.executable}; each timed as its whole process's CPU time, paired with the second):")
    for name, (first, second) in zip([row[0] for row in rows], [
        (compile_plain, gcodeparser), (compile_expressions, bare), (lint_expressions, bare), (lint_walk, bare),
        (lint_small, bare),
    ]):
        print(f"  {name}: {shown(first)}  vs  {shown(second)}")
    print("reproduce: .venv/bin/python benchmarks/cli_speed.py "
          f"--lines {options.lines} --compile-lines {options.compile_lines} "
          f"--expression-lines {options.expression_lines} --pairs {options.pairs} --seed {options.seed}")
    return 1 if options.check and not all(ok for *_, ok, _ in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
