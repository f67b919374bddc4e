"""Calls per second of the closed-form IK (armctl/core/kinematics.py's one flat solver, issues 11, 13).

  inverse, path      the simulator's case: poses along benchmarks/virtual_run.py's job (X250,
                     Y −50…50, Z150, tool down), each hinted by the joints before it, the default
                     profile's limits (13,372 such calls in that 20-minute job)
  inverse, mixed     arbitrary poses (fixed seed), many out of reach or outside the limits
  has_solution, …    lint's question, on the same two sets

CPU time (``time.process_time``) of this process, the median of ``--repeats`` passes: other
processes on a shared machine disturb it far less than the wall time.  Compare two trees in one
session, alternating, as the README's figures were taken.

    .venv/bin/python benchmarks/ik_speed.py
    .venv/bin/python benchmarks/ik_speed.py --repeats 15
"""

from __future__ import annotations

import argparse
import random
import statistics
import sys
import time

POSES = 4000


def workloads():
    from armctl.core.kinematics import Unreachable, has_solution, inverse
    from armctl.host.profile import default_profile

    profile = default_profile()
    links, limits, home = profile.links, profile.joint_limits_deg, tuple(profile.poses[0])
    path = [(250.0, -50.0 + 100.0 * k / POSES, 150.0, 180.0, 0.0, 0.0) for k in range(POSES)]
    rng = random.Random(1)
    mixed = [(rng.uniform(-450, 450), rng.uniform(-450, 450), rng.uniform(-100, 600),
              rng.uniform(-180, 180), rng.uniform(-180, 180), rng.uniform(-180, 180)) for _ in range(POSES)]

    def inverse_path():
        near = home
        for pose in path:
            near = inverse(pose, links, near, limits)

    def inverse_mixed():
        for pose in mixed:
            try:
                inverse(pose, links, home, limits)
            except Unreachable:
                pass

    def has_solution_of(poses):
        return lambda: [has_solution(pose, links, home, limits) for pose in poses]

    return [("inverse, path", inverse_path), ("inverse, mixed", inverse_mixed),
            ("has_solution, path", has_solution_of(path)), ("has_solution, mixed", has_solution_of(mixed))]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    for name, run in workloads():
        seconds = []
        for _ in range(args.repeats):
            start = time.process_time()
            run()
            seconds.append(time.process_time() - start)
        median_s = statistics.median(seconds)
        rate = f"{POSES / median_s:,.0f}" if median_s > 0 else "too fast to time"
        print(f"{name:<20} {rate} calls/s (CPU, median of {args.repeats})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
