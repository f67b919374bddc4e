"""The streaming benchmark, as a script: ``python benchmarks/streaming.py [--quick] …``.

The same click command as ``armctl bench`` and ``python -m armctl.bench``; see docs/bench.md for
what it measures.
"""

from armctl.ui.cli import bench

if __name__ == "__main__":
    bench(prog_name="python benchmarks/streaming.py")
