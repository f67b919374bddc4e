"""Does ``armctl lint`` stay flat in memory on a very long script?  Peak RSS and lines/s.

Generates scripts in a temporary directory and lints each with the ``lint`` click command in
its own subprocess (output to /dev/null), so every peak RSS is that run's own:

  clean    N reachable G1 moves (tool down, varying targets, comments): every rule runs on
           every line, IK included, and nothing is reported
  noisy    the same moves, each with F30 (L203, a warning on every line) and every 10th with
           an unknown word (E002): N findings, of which lint keeps the first 1000 per file

Each kind is run at a small size (--baseline lines) and at N; "flat" means the peak RSS of the
long run is within --max-growth MB of the short one.  Exit 1 when it is not (with --check).

    .venv/bin/python benchmarks/lint_memory.py                  # 1,000,000 lines (a few minutes)
    .venv/bin/python benchmarks/lint_memory.py --lines 100000 --check
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_LINES = 1_000_000

_CHILD = """
import json, resource, sys, time
from armctl.lint.command import lint
start = time.perf_counter()
code = lint.main(args=sys.argv[1:], standalone_mode=False)
seconds = time.perf_counter() - start
print(json.dumps({"seconds": seconds, "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "exit": code}), file=sys.stderr)
"""


def _sweep(index: int, step: int, span: int) -> int:
    """Back and forth over ``span`` in ``step``s: where the ``index``-th step lands (0 … span)."""
    at = index * step % (2 * span)
    return at if at <= span else 2 * span - at


def write_script(path: Path, lines: int, noisy: bool) -> None:
    """Reachable tool-down moves over a 200 × 300 × 180 mm box, each a short step from the one
    before (0.3, 0.2 and 0.1 mm along X, Y and Z, back and forth: 36,000 distinct targets, few
    repeats).  Short: the job must stay within E012's bound of motion (24 hours), or the clean
    script is not clean — jumps across the box took 1.7 s each, E012 at line 50,142."""
    with open(path, "w", encoding="utf-8") as out:
        out.write("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000 ; start from a known pose\n")
        for index in range(1, lines):
            x = (1500 + _sweep(index + 333, 3, 2000)) / 10  # in tenths of a mm; from near the start pose
            y = (-1500 + _sweep(index + 750, 2, 3000)) / 10
            z = (200 + _sweep(index + 1300, 1, 1800)) / 10
            speed = " F30" if noisy else (" F3000" if index % 5 == 0 else "")
            unknown = " Q1" if noisy and index % 10 == 0 else ""
            comment = f" ; point {index}" if index % 4 == 0 else ""
            out.write(f"G1 X{x} Y{y} Z{z}{speed}{unknown}{comment}\n")


def run(path: Path) -> dict:
    child = subprocess.run(
        [sys.executable, "-c", _CHILD, str(path), "--statistics"],
        cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, check=False,
    )
    last = child.stderr.strip().splitlines()[-1]
    return json.loads(last)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lines", type=int, default=DEFAULT_LINES)
    parser.add_argument("--baseline", type=int, default=10_000)
    parser.add_argument("--max-growth", type=float, default=10.0, help="MB the long run may add (default 10)")
    parser.add_argument("--check", action="store_true", help="exit 1 if memory is not flat")
    options = parser.parse_args(argv)
    flat = True
    print(f"{'script':<8} {'lines':>10} {'seconds':>8} {'lines/s':>9} {'peak RSS MB':>12} {'exit':>5}")
    with tempfile.TemporaryDirectory() as directory:
        for kind in ("clean", "noisy"):
            results = []
            for lines in (options.baseline, options.lines):
                path = Path(directory) / f"{kind}_{lines}.txt"
                write_script(path, lines, kind == "noisy")
                started = time.perf_counter()
                result = run(path)
                result.setdefault("seconds", time.perf_counter() - started)
                results.append(result)
                print(f"{kind:<8} {lines:>10,} {result['seconds']:>8.1f} {lines / result['seconds']:>9,.0f}"
                      f" {result['rss_mb']:>12.1f} {result['exit']:>5}")
                path.unlink()
            growth = results[1]["rss_mb"] - results[0]["rss_mb"]
            verdict = "flat" if growth <= options.max_growth else "GROWS"
            flat &= growth <= options.max_growth
            print(f"{'':<8} {'':>10} peak RSS {growth:+.1f} MB from {options.baseline:,} to {options.lines:,} lines: {verdict}")
    return 0 if flat or not options.check else 1


if __name__ == "__main__":
    sys.exit(main())
