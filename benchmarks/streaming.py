"""The streaming benchmark, as a script: ``python benchmarks/streaming.py [--quick] …``.

A thin wrapper over ``armctl.bench.table.main`` (the same code as ``python -m armctl.bench``);
see docs/bench.md for what it measures.
"""

import sys

from armctl.bench.table import main

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
