"""What the tests/test_claims_*.py files share: a job that outruns a small FIFO, and a fresh
process of the installed package (``python -m armctl …`` or a program using its API)."""

from __future__ import annotations

import os
import subprocess
import sys


def raster(moves: int) -> str:
    """Rows of 8 mm moves (80 ms at 6000 mm/min), each to a target of its own: more frames than a
    60-frame FIFO holds within a 6 s lead."""
    lines, x, y = ["G1 X200 Y-100 Z150 A180 B0 C0 S1500 F6000"], 200, -100
    for k in range(moves - 1):
        if k % 25 == 24:
            x += 8
        else:
            y += 8 if (k // 25) % 2 == 0 else -8
        lines.append(f"G1 X{x} Y{y} Z150")
    return "\n".join(lines) + "\n"


def fresh(args: list[str], cwd, timeout_s: float = 60.0) -> subprocess.CompletedProcess:
    """``python args…`` in a fresh process (no ARMCTL_PORT: the port is the test's)."""
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    return subprocess.run([sys.executable, *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout_s)
