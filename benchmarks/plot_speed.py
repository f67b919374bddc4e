"""How long ``armctl plot`` takes on the example jobs (issue 26: under 1.5 s each).

Runs the installed command on every scripts/*.txt job for each output format, --repeat times,
in alternating order, and prints the median wall and CPU time (user + system of the process) of
each, next to a baseline measured in the same run: a bare process importing what the format's
library needs (matplotlib's Figure for SVG/PNG, plotly for HTML) — the part no change to armctl
can remove — so the figures read on a loaded machine too.

    .venv/bin/python benchmarks/plot_speed.py                  # svg, png, html; 3 runs each
    .venv/bin/python benchmarks/plot_speed.py --formats svg png --repeat 5
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ARMCTL = Path(sys.executable).with_name("armctl")
BASELINE = {"svg": "import matplotlib.figure", "png": "import matplotlib.figure", "html": "import plotly.graph_objects"}


def timed(args: list[str]) -> tuple[float, float]:
    """(wall s, CPU s) of one child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(args, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--formats", nargs="+", default=["svg", "png", "html"], choices=["svg", "png", "html"])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    jobs = sorted((ROOT / "scripts").glob("*.txt"))
    worst = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        for fmt in args.formats:
            runs: dict[str, list[tuple[float, float]]] = {job.name: [] for job in jobs}
            base: list[tuple[float, float]] = []
            for _ in range(args.repeat):
                base.append(timed([sys.executable, "-c", BASELINE[fmt]]))
                for job in jobs:
                    runs[job.name].append(timed([str(ARMCTL), "plot", str(job), "-o", os.path.join(tmp, f"out.{fmt}")]))
            base_wall = statistics.median(w for w, _ in base)
            base_cpu = statistics.median(c for _, c in base)
            print(f"{fmt}: baseline `{BASELINE[fmt]}` {base_wall:.2f} s wall, {base_cpu:.2f} s CPU")
            for name, measured in runs.items():
                wall = statistics.median(w for w, _ in measured)
                cpu = statistics.median(c for _, c in measured)
                worst = max(worst, wall)
                print(f"  {name:26} {wall:5.2f} s wall  {cpu:5.2f} s CPU  ({cpu / base_cpu:4.1f}x the baseline's CPU)")
    print(f"slowest: {worst:.2f} s wall (target < 1.5 s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
