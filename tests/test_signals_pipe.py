"""Issue 22: ``armctl run --json | head -1`` exited 141 having sent the pause toggle, but "the
abort did not complete" (the next event's write broke the abort's wait for the arm), and the
resume line it printed was still queued on the arm.  Now the broken pipe stops the job the way
Ctrl-C does — the abort sequence, then the wait for the arm at rest — and the summary and resume
line go to stderr, from the arm's reports; exit 141.

Through the installed command in a fresh process, on the virtual clock (model time): the reader
takes the first line and closes its end of the pipe, as ``head -1`` does.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ARMCTL = [str(Path(sys.executable).with_name("armctl"))]
TIMEOUT_S = 60


def test_a_reader_that_goes_away_gets_the_whole_abort_and_a_true_resume_line(tmp_path):
    log = tmp_path / "job.log"
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    process = subprocess.Popen([*ARMCTL, "run", "--json", "scripts/pick_and_place.txt", "--port", "sim://?clock=virtual",
                                "--log", str(log)], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        first = json.loads(process.stdout.readline())
        process.stdout.close()  # head -1 has its line and exits
        err = process.stderr.read().decode()
        code = process.wait(timeout=TIMEOUT_S)
    finally:
        process.kill()
    assert first["event"] == "started"
    assert code == 141, err
    assert "Traceback" not in err and "the abort did not complete" not in err, err
    assert "note: the program reading --json went away" in err
    assert "stopped: interrupted; abort sequence: pause" in err, err

    records = [json.loads(line) for line in log.read_text().splitlines()]
    abort = next(k for k, r in enumerate(records) if r.get("abort"))
    assert records[abort]["hex"].startswith("fc1e0302")  # the pause toggle went
    assert not any(r["dir"] == "tx" for r in records[abort + 1:])  # and nothing after it
    heard = [r["t"] for r in records[abort + 1:] if r["dir"] == "rx"]
    assert heard and heard[-1] - records[abort]["t"] >= 1.0  # the arm was heard until it came to rest
    progress = [r for r in records if r["dir"] == "progress"][-1]
    resume = next(line for line in err.splitlines() if line.startswith("resume with: "))
    assert f"--from-line {progress['done_resume']} " in resume, (resume, progress)
    assert progress["done_n"] == progress["frames_sent"], progress  # at rest: every frame written ran
