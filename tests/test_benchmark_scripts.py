"""The benchmark scripts the README shows say what to install instead of a traceback.

benchmarks/cli_speed.py (issue 13's rows, gcodeparser the reference of one) does the same.

Issue 10: ``python benchmarks/compile_speed.py`` as the README showed it ended in
ModuleNotFoundError (gcodeparser, the bench extra, was never installed).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

def _load(script: str):
    import importlib.util

    spec = importlib.util.spec_from_file_location(script.removesuffix(".py"), ROOT / "benchmarks" / script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def without_gcodeparser(script: str) -> str:
    """Runs ``script`` as __main__ with gcodeparser hidden, as on an install without the extra."""
    path = ROOT / "benchmarks" / script
    return (
        "import runpy, sys; sys.modules['gcodeparser'] = None; "
        f"sys.argv = [{str(path)!r}, '--lines', '10']; "
        "runpy.run_path(sys.argv[0], run_name='__main__')"
    )


@pytest.mark.parametrize("script", ["compile_speed.py", "cli_speed.py"])
def test_benchmarks_without_the_bench_extra_say_what_to_install(script):
    done = subprocess.run([sys.executable, "-c", without_gcodeparser(script)], capture_output=True, text=True,
                          timeout=60, cwd=ROOT)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    assert "pip install -e '.[bench]'" in done.stderr
    assert done.stdout == ""  # nothing generated or measured


def test_readme_installs_the_bench_extra_before_the_benchmark():
    readme = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    run = next(i for i, line in enumerate(readme) if "benchmarks/compile_speed.py" in line and line.startswith("$"))
    assert "pip install -e '.[bench]'" in readme[run - 1]


def test_virtual_run_baseline_replays_frames_on_the_simulator():
    # issue 11's row (benchmarks/virtual_run.py) broke silently when parse_sim_url changed
    # shape: its baseline is run here on a second of arm time.
    from armctl.core.protocol import Delay

    wall_s, cpu_s = _load("virtual_run.py").baseline([(0.0, Delay(500).encode())], 1.0)
    assert wall_s > 0 and cpu_s >= 0


def test_virtual_run_cost_times_the_installed_command_in_a_fresh_process(tmp_path):
    # issue 23's measure (virtual_run.py --cost): its job and its child's CPU, on a job of 2 passes
    module = _load("virtual_run.py")
    script = tmp_path / "job.txt"
    module.write_cost_job(script)
    assert "O<a> repeat [12000]" in script.read_text()
    script.write_text(script.read_text().replace("[12000]", "[2]"))
    assert module.child_cpu_s("compile", str(script)) > 0
    with pytest.raises(SystemExit, match="exit 2"):  # a failing child stops the benchmark, saying why
        module.child_cpu_s("compile", str(tmp_path / "missing.txt"))


def test_virtual_run_split_counts_the_engine_and_the_port_and_puts_them_back(monkeypatch, capsys):
    # virtual_run.py --split on a job of 2 passes: every part counted, the methods restored after
    from armctl.core.job import Job
    from armctl.sim.protocol_sim import Serial

    module = _load("virtual_run.py")
    monkeypatch.setattr(module, "COST_PASSES", 2)
    before = [Job.next_action, Job.receive_statuses, Job.wrote, Serial.advance_to, Serial.write]
    run_s, engine_s, simulator_s, base_s = module.split(1)
    assert 0 < engine_s < run_s and 0 < simulator_s < run_s and base_s > 0
    assert "job: 5 frames" in capsys.readouterr().out
    assert [Job.next_action, Job.receive_statuses, Job.wrote, Serial.advance_to, Serial.write] == before


def test_streamer_cost_builds_its_streamers_and_times_a_batch():
    # benchmarks/streamer_cost.py (issue 13's flat-cost row) called a private streamer method
    # whose signature had changed, and ended in a TypeError unnoticed: its code runs here.
    module = _load("streamer_cost.py")
    streamer, frames, now = module.loaded_streamer(9)
    assert len(streamer.pending) == 9
    assert module.batch_seconds(streamer, frames, now) > 0
    assert len(streamer.pending) == 9  # the probe consumes nothing, as main() asserts for 185


def test_ik_speed_workloads_run():
    module = _load("ik_speed.py")
    for name, work in module.workloads():
        work()


def test_the_clean_script_of_lint_memory_lints_clean(tmp_path):
    """benchmarks/lint_memory.py measures lint on a "clean" script, one that reports nothing — but
    its moves jumped across the box (1.7 s of motion each), so at its default 1,000,000 lines the
    job passed E012's 24 hours of motion at line 50,142.  Cheap: a small script lints with no
    finding at all, and its motion time a line, at the default size, stays well within E012."""
    import json

    from click.testing import CliRunner

    from armctl.script.source import MAX_JOB_MOTION_S
    from armctl.ui.cli import main

    bench = _load("lint_memory.py")
    path = tmp_path / "clean.txt"
    lines = 2_000
    bench.write_script(path, lines, noisy=False)
    linted = CliRunner().invoke(main, ["lint", "--json", str(path)])
    assert linted.exit_code == 0 and json.loads(linted.stdout) == [], linted.output
    estimated = CliRunner().invoke(main, ["estimate", "--json", str(path)])
    motion_s = json.loads(estimated.stdout)["motion_s"]
    assert motion_s / lines * bench.DEFAULT_LINES < MAX_JOB_MOTION_S / 2, motion_s
