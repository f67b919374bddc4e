"""The benchmark scripts the README shows say what to install instead of a traceback.

Issue 10: ``python benchmarks/compile_speed.py`` as the README showed it ended in
ModuleNotFoundError (gcodeparser, the bench extra, was never installed).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# Runs the script as __main__ with gcodeparser hidden, as on an install without the extra.
SCRIPT = ROOT / "benchmarks" / "compile_speed.py"
WITHOUT_GCODEPARSER = (
    "import runpy, sys; sys.modules['gcodeparser'] = None; "
    f"sys.argv = [{str(SCRIPT)!r}, '--lines', '10']; "
    "runpy.run_path(sys.argv[0], run_name='__main__')"
)


def test_compile_speed_without_the_bench_extra_says_what_to_install():
    done = subprocess.run([sys.executable, "-c", WITHOUT_GCODEPARSER], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    assert "pip install -e '.[bench]'" in done.stderr
    assert done.stdout == ""  # nothing generated or measured


def test_readme_installs_the_bench_extra_before_the_benchmark():
    readme = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    run = next(i for i, line in enumerate(readme) if "benchmarks/compile_speed.py" in line and line.startswith("$"))
    assert "pip install -e '.[bench]'" in readme[run - 1]
