"""Behaviour digests that a refactoring must leave identical (issue 23: one pipeline, behaviour
unchanged).

Two digests are recorded in ``benchmarks/digests.json`` before the redesign and checked after it:

  frames   every frame the simulated arm received, with the model time it landed, for every job in
           scripts/ on several ``sim://`` arm variants (``armctl run JOB --no-live --port URL`` in this
           process, virtual clock), plus the summary's arm time line: one digest per job × variant.
           The hook is the simulator's own input (``SimulatedArm.write``), below every host layer,
           so it sees what reached the arm whatever path the host took to send it.
  bench    the full ``armctl bench --json`` table, run as the installed command, its wall time left out.

The third, the fidelity digests (the engine's reads and writes with their model times), lives in
tests/test_virtual_fidelity.py and runs with the suite.  tests/test_frames_digests.py checks the
frames digests in the suite too; the bench digest is checked here only (the full bench takes a while).

    .venv/bin/python benchmarks/digests.py            # check both against digests.json
    .venv/bin/python benchmarks/digests.py --frames   # the frames only (about 20 s)
    .venv/bin/python benchmarks/digests.py --record   # write digests.json anew (only for a real change of behaviour)
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = ROOT / "scripts"
RECORD = Path(__file__).resolve().parent / "digests.json"

VARIANTS = {  # the arm behaviours the document leaves open, each a sim:// impersonation
    "default": "sim://?clock=virtual",
    "arrival": "sim://?clock=virtual&control=arrival",
    "slow": "sim://?clock=virtual&speed_factor=1.3",
    "fast_line": "sim://?clock=virtual&baud=115200&fifo_frames=50",
    "robot_xyz": "sim://?clock=virtual&status_xyz_frame=robot",
    "faults": "sim://?clock=virtual&noise=0.05&loss=0.02&corrupt=0.02&seed=7",
}


def frames_digest(script: str, url: str) -> str:
    """The digest of one run: every frame the simulated arm received with its model time, the
    exit code and the summary's arm time."""
    from click.testing import CliRunner

    from armctl.ui.cli import main
    from armctl.sim.model import SimulatedArm

    events: list[str] = []
    write = SimulatedArm.write

    def recording(self, data, now_s):
        events.append(f"{now_s!r} {bytes(data).hex()}")
        return write(self, data, now_s)

    SimulatedArm.write = recording
    cwd = os.getcwd()
    try:
        os.chdir(ROOT)  # the script named as given, relative: the same in any checkout
        rate = re.search(r"[?&]baud=(\d+)", url)  # the port set to the arm's rate, as a user of that arm sets it
        result = CliRunner().invoke(main, ["run", f"scripts/{script}", "--no-live", "--port", url,
                                           *(["--baud", rate.group(1)] if rate else [])],
                                    env={"ARMCTL_PORT": None, "ARMCTL_CONFIG": None})
    finally:
        SimulatedArm.write = write
        os.chdir(cwd)
    arm_time = re.search(r"^arm time: .*$", result.stdout, re.M)
    events.append(f"exit {result.exit_code}")
    events.append(arm_time.group(0) if arm_time else "no arm time")
    return hashlib.sha256("\n".join(events).encode()).hexdigest()[:16]


def all_frames_digests() -> dict[str, str]:
    return {f"{path.stem}@{variant}": frames_digest(path.name, url)
            for path in sorted(SCRIPTS.glob("*.txt")) for variant, url in VARIANTS.items()}


def bench_digest() -> str:
    armctl = Path(sys.executable).with_name("armctl")
    command = [str(armctl)] if armctl.exists() else [sys.executable, "-m", "armctl"]
    done = subprocess.run(command + ["bench", "--json"], capture_output=True, text=True, cwd=ROOT, timeout=600)
    table = json.loads(done.stdout)
    table.pop("wall_s", None)
    return hashlib.sha256(json.dumps(table, sort_keys=True).encode()).hexdigest()[:16]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", action="store_true", help="write digests.json anew")
    parser.add_argument("--frames", action="store_true", help="the frames digests only")
    args = parser.parse_args()
    now = {"frames": all_frames_digests()}
    if not args.frames:
        now["bench"] = bench_digest()
    if args.record:
        RECORD.write_text(json.dumps(now, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        print(f"recorded {len(now['frames'])} frames digests and the bench digest in {RECORD.name}")
        return 0
    kept = json.loads(RECORD.read_text(encoding="utf-8"))
    differ = [name for name, digest in now["frames"].items() if kept["frames"].get(name) != digest]
    if "bench" in now and now["bench"] != kept["bench"]:
        differ.append("bench")
    for name in differ:
        print(f"DIFFERS: {name}")
    checked = len(now["frames"]) + ("bench" in now)
    print(f"{checked - len(differ)} of {checked} digests identical")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
