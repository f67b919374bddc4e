"""Peak memory of a long virtual run does not grow with the job.

``python benchmarks/sim_memory.py`` streams 1,000 and then 50,000 tiny moves (1 mm, 10 ms each,
round a 1 mm square; the job is generated as it is read, so only what the run keeps counts)
through armctl's streamer to the simulated arm in virtual time, each run in a fresh process, and
prints both peak RSS figures and their ratio (flat means about 1).  ``--frames N`` runs one job
in this process and prints its peak RSS in KB (what the parent reads).
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys

SIZES = (1_000, 50_000)


class SquareJob:
    """``frames`` 1 mm moves round a square at 6000 mm/min, made when indexed."""

    CORNERS = ((250.0, 0.0, 150.0), (251.0, 0.0, 150.0), (251.0, 1.0, 150.0), (250.0, 1.0, 150.0))

    def __init__(self, frames: int) -> None:
        self.frames = frames

    def __len__(self) -> int:
        return self.frames

    def __getitem__(self, index: int):
        from armctl.bench.scenarios import _line

        if not 0 <= index < self.frames:
            raise IndexError(index)
        return _line(self.CORNERS[index % 4], 6000.0)


def one_run(frames: int) -> int:
    from armctl.bench.harness import run_job
    from armctl.bench.strategies import StreamerStrategy
    from armctl.core.motion import MotionModel
    from armctl.sim.model import SimOptions, SimulatedArm

    arm = SimulatedArm(SimOptions())
    strategy = StreamerStrategy(MotionModel(arm.profile), arm.pose, 2.0)
    result = run_job(SquareJob(frames), strategy, arm, time_limit_s=frames * 1.0)
    assert result.dropped == 0 and not result.timed_out and result.written == frames
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KB on Linux


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, help="run one job here and print its peak RSS in KB")
    args = parser.parse_args()
    if args.frames:
        print(one_run(args.frames))
        return 0
    peaks = {}
    for frames in SIZES:
        done = subprocess.run([sys.executable, __file__, "--frames", str(frames)], capture_output=True, text=True,
                              timeout=600, check=True)
        peaks[frames] = int(done.stdout.split()[-1])
        print(f"{frames:>6} frames: peak RSS {peaks[frames] / 1024:.1f} MB")
    ratio = peaks[SIZES[1]] / peaks[SIZES[0]]
    print(f"peak RSS, {SIZES[1]:,} frames ÷ {SIZES[0]:,} frames: {ratio:.2f} (fresh processes; flat = 1.00)")
    print("reproduce: python benchmarks/sim_memory.py")
    return 0


if __name__ == "__main__":
    sys.exit(main())
