"""How much memory does ``--resume LOG`` take to read a long log?  The read's peak and its CPU.

A resume read its log whole and kept every frame's record: 549 MB of peak RSS for a 115 MB log,
and any log over 128 MiB (a job longer than about 5.4 hours) was refused.  This writes a log as
``run --log`` does (a job record; each frame's record with its target; two status records a
frame) at a small size and at --frames, reads each with ``read_resume_point`` in its own
subprocess (twice: once timed, once with tracemalloc counting the read's own peak, past what
the interpreter, armctl and the script it checks the log against hold — a 600,000-line script
is 30 MB itself), and prints the read's peak, the process's peak RSS, the CPU seconds and the
read's peak as a share of the log's size (exit 1 with --check when it passes --max-ratio).
tests/test_resume_long_log.py checks the mechanism; this measures it.

    .venv/bin/python benchmarks/resume_memory.py                       # 600,000 frames: ~307 MB
    .venv/bin/python benchmarks/resume_memory.py --frames 100000 --check
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_CHILD = """
import json, resource, sys, time, tracemalloc
from armctl.host.jobflow import read_resume_point
from armctl.script.files import ScriptSnapshot
snapshot = ScriptSnapshot("job.txt", open(sys.argv[2], "rb").read())
if sys.argv[3] == "memory":  # the read's own peak, past what was held before it (the script: 30 MB at 600,000 lines)
    tracemalloc.start()
    read_resume_point(sys.argv[1], snapshot)
    print(json.dumps({"read_mb": tracemalloc.get_traced_memory()[1] / 2**20}))
else:
    start = time.process_time()
    point = read_resume_point(sys.argv[1], snapshot)
    print(json.dumps({"frames": len(point.frames), "cpu_s": time.process_time() - start,
                      "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def write_log(path: Path, script: Path, frames: int) -> int:
    """A log of ``frames`` frames of a script of as many lines, written a record at a time (a
    child's peak RSS counts the memory its parent held when it forked: the parent stays small)."""
    from armctl.core.joblog import job_record, seal, target_of

    data = "".join(f"G1 X{200 + k % 50} Y0 Z250 A180 B0 C0 S1500 F3000\n" for k in range(frames)).encode()
    script.write_bytes(data)
    status = {"t": 0.0, "dir": "rx", "hex": "a5" + "00" * 7 + "5a"}
    with open(path, "w", encoding="utf-8") as out:
        out.write(seal(job_record("job.txt", data, 1, 2.0, frames), 0) + "\n")
        seq = 1
        for k in range(1, frames + 1):
            target = target_of("line", (200.0 + (k - 1) % 50, 0.0, 250.0), (0.0,) * 6)
            out.write(seal({"t": k * 0.05, "dir": "tx", "hex": "ee" * 48, "line": k, "n": k, "at": k,
                            "next": k + 1 if k < frames else None, "target": target}, seq) + "\n")
            out.write(seal(status, seq + 1) + "\n" + seal(status, seq + 2) + "\n")
            seq += 3
    return path.stat().st_size


def run(log: Path, script: Path, what: str) -> dict:
    child = subprocess.run([sys.executable, "-c", _CHILD, str(log), str(script), what], cwd=ROOT, capture_output=True,
                           text=True, check=False)
    if child.returncode != 0:
        raise SystemExit(f"the resume read failed: {child.stderr}")
    return json.loads(child.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=600_000, help="frames of the large log")
    parser.add_argument("--baseline-frames", type=int, default=10_000, help="frames of the small log")
    parser.add_argument("--max-ratio", type=float, default=0.25, help="the read's peak ÷ the log's size, at most")
    parser.add_argument("--check", action="store_true")
    args = parser.parse_args()
    peaks = []
    with tempfile.TemporaryDirectory() as tmp:
        for frames in (args.baseline_frames, args.frames):
            log, script = Path(tmp) / f"{frames}.log", Path(tmp) / f"{frames}.txt"
            size = write_log(log, script, frames)
            result = run(log, script, "time")
            read_mb = run(log, script, "memory")["read_mb"]
            peaks.append(read_mb * 2**20 / size)
            print(f"{frames:>9,} frames  log {size / 1e6:7.1f} MB  the read's peak {read_mb:6.1f} MB (traced), the "
                  f"process's peak RSS {result['rss_mb']:6.1f} MB  CPU {result['cpu_s']:5.1f} s  "
                  f"{frames / max(result['cpu_s'], 1e-9):>9,.0f} frames/s")
            log.unlink()
    ratio = peaks[-1]  # (the small log's shows the fixed part: a read block of 1 MiB and its lines)
    print(f"the read's peak ÷ the log's size: {peaks[0]:.3f} small, {ratio:.3f} large (target <= {args.max_ratio} for the "
          "large; it keeps each frame's line, at and next, 24 bytes, and the last two targets — the whole log was held "
          "before: 549 MB of peak RSS for 115 MB)")
    return 1 if args.check and ratio > args.max_ratio else 0


if __name__ == "__main__":
    sys.exit(main())
