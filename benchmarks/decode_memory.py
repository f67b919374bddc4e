"""Does ``armctl decode`` stay flat in memory as its input grows?  Peak RSS and frames/s.

Issue 22: 12 MB of status frames took 25 s and 675 MB (about 7 GB at the 128 MiB input cap),
because every frame was kept.  This generates raw status frames (the worst case: 9 bytes a
frame) and a run-log of them at a small size and at --mb, decodes each with the ``decode`` click
command in its own subprocess (output to /dev/null), and prints each run's peak RSS and the
ratio large ÷ small.  "Flat" means the ratio stays near 1 (exit 1 with --check when it passes
--max-ratio).

    .venv/bin/python benchmarks/decode_memory.py                 # 12 MB, as in the issue
    .venv/bin/python benchmarks/decode_memory.py --mb 4 --check
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STATUS = bytes.fromhex("ce083400000bb800cf")

_CHILD = """
import json, resource, sys, time
from armctl.ui.cli import main
start = time.perf_counter()
try:
    main.main(args=["decode", *sys.argv[1:]], standalone_mode=False)
finally:
    print(json.dumps({"seconds": time.perf_counter() - start,
                      "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}), file=sys.stderr)
"""


def _write_repeated(path: Path, piece: bytes, megabytes: float) -> int:
    """``piece`` repeated to ``megabytes``, written a megabyte at a time: a child's peak RSS
    counts the memory its parent held when it forked, so the parent must stay small."""
    count = int(megabytes * 1e6 / len(piece))
    per_write = max(1, 1_000_000 // len(piece))
    with open(path, "wb") as out:
        for start in range(0, count, per_write):
            out.write(piece * min(per_write, count - start))
    return count


def write_raw(path: Path, megabytes: float) -> int:
    return _write_repeated(path, STATUS, megabytes)


def write_log(path: Path, megabytes: float) -> int:
    line = json.dumps({"t": 0.03, "dir": "rx", "hex": STATUS.hex(), "kind": 0}) + "\n"
    return _write_repeated(path, line.encode(), megabytes)


def run(path: Path) -> dict:
    child = subprocess.run([sys.executable, "-c", _CHILD, str(path)], cwd=ROOT, stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, text=True, check=False)
    return json.loads(child.stderr.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mb", type=float, default=12.0, help="size of the large input, MB")
    parser.add_argument("--baseline-mb", type=float, default=1.2, help="size of the small input, MB")
    parser.add_argument("--max-ratio", type=float, default=1.5)
    parser.add_argument("--check", action="store_true")
    args = parser.parse_args()
    worst = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        for kind, write in (("raw", write_raw), ("log", write_log)):
            peaks = []
            for megabytes in (args.baseline_mb, args.mb):
                path = Path(tmp) / f"{kind}-{megabytes}"
                frames = write(path, megabytes)
                result = run(path)
                peaks.append(result["rss_mb"])
                print(f"{kind:4} {megabytes:6.1f} MB  {frames:>9,} frames  peak RSS {result['rss_mb']:7.1f} MB  "
                      f"{result['seconds']:6.1f} s  {frames / result['seconds']:>9,.0f} frames/s")
            ratio = peaks[1] / peaks[0]
            worst = max(worst, ratio)
            print(f"{kind:4} peak RSS ratio {args.mb:g} MB ÷ {args.baseline_mb:g} MB: {ratio:.2f} (flat: <= {args.max_ratio})")
    return 1 if args.check and worst > args.max_ratio else 0


if __name__ == "__main__":
    sys.exit(main())
