"""Issue 24 item 1 through the installed command, each step a fresh process: ``armctl probe``
keeps what it measured with the arm, and every command on that arm — and only on that arm —
uses it; ``--write`` names the arm; ``config`` names the source of every connector value;
``probe --list`` / ``--forget``; ``bench`` reads no configuration at all."""

from __future__ import annotations

import datetime
import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

pytestmark = pytest.mark.timeout(90)

ROOT = Path(__file__).resolve().parents[1]
JOB = ROOT / "scripts" / "draw_square_circle.txt"
ARM = "sim://?fifo_frames=50&speed_factor=1.3"  # the arm's identity: its options, canonical, no clock
PORT = "sim://?clock=virtual&fifo_frames=50&speed_factor=1.3"
OTHER = "sim://?clock=virtual"
DONE = "finished: the arm finished the job"


def armctl(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    return subprocess.run([sys.executable, "-m", "armctl", *args], capture_output=True, text=True, timeout=80,
                          cwd=cwd, env=env)


def probe(cwd: Path, *extra: str) -> subprocess.CompletedProcess:
    done = armctl("probe", "--port", PORT, "--yes", *extra, cwd=cwd)
    assert done.returncode == 0, done.stderr
    return done


def summary(result: subprocess.CompletedProcess) -> list[str]:
    """The run's stdout without its wall time (the one line that differs between two runs)."""
    return [line for line in result.stdout.splitlines() if not line.startswith("time: ")]


def test_probe_then_run_on_that_arm_ends_done_without_write(tmp_path):
    before = armctl("run", str(JOB), "--no-live", "--port", PORT, cwd=tmp_path)
    assert before.returncode == 1 and before.stdout.splitlines()[-1].startswith("finished, unproven")
    other_before = armctl("run", str(JOB), "--no-live", "--port", OTHER, cwd=tmp_path)

    shown = probe(tmp_path)
    assert f"kept for {ARM} in " in shown.stdout
    assert list(tmp_path.iterdir()) == []  # nothing written to the directory
    run = armctl("run", str(JOB), "--no-live", "--port", PORT, cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.splitlines()[-1] == DONE

    other = armctl("run", str(JOB), "--no-live", "--port", OTHER, cwd=tmp_path)  # another arm: unaffected
    assert other.returncode == other_before.returncode == 0
    assert summary(other) == summary(other_before)


def test_the_clock_and_the_spelling_of_the_url_are_not_the_arm(tmp_path):
    probe(tmp_path)
    run = armctl("run", str(JOB), "--no-live", "--port", "sim://?speed_factor=1.30&fifo=50&clock=virtual", cwd=tmp_path)
    assert run.stdout.splitlines()[-1] == DONE, run.stdout + run.stderr


def test_config_names_the_source_of_every_connector_value(tmp_path):
    probe(tmp_path)
    today = datetime.datetime.now(datetime.timezone.utc).date().isoformat()  # the probe's date (UTC)
    shown = json.loads(armctl("config", "--json", "--port", PORT, cwd=tmp_path).stdout)["settings"]
    connector = {k: v for k, v in shown.items() if k.startswith("connector.")}
    assert len(connector) == 7
    # every value the probe measures (not status_jitter_ms: a port's reads are later than it)
    assert connector.pop("connector.status_jitter_ms")["value"] == 1.0
    for name, setting in connector.items():
        assert setting["source"] == "probe", (name, setting)
        assert setting["where"] in (f"probed on {day} for {ARM}" for day in (today, _yesterday(today)))
    assert connector["connector.fifo_frames"]["value"] == 50

    (tmp_path / "armctl.toml").write_text(f'[connector]\nmeasured_on = "{ARM}"\nspeed_factor = 1.25\n')
    text = armctl("config", "--port", PORT, cwd=tmp_path).stdout.splitlines()
    assert f"connector.speed_factor 1.25  (project: {tmp_path / 'armctl.toml'})" in text
    assert any(line.startswith("connector.fifo_frames 50  (probed on ") and line.endswith(f" for {ARM})") for line in text)
    elsewhere = armctl("config", "--port", OTHER, cwd=tmp_path).stdout.splitlines()
    assert "connector.fifo_frames 200  (the document's default)" in elsewhere
    assert "connector.speed_factor 1.0  (the document's default)" in elsewhere


def _yesterday(today: str) -> str:
    return (datetime.date.fromisoformat(today) - datetime.timedelta(days=1)).isoformat()  # a probe at midnight


def test_write_names_the_arm_and_the_file_applies_on_that_arm_only(tmp_path):
    """The issue's first finding: after ``probe --write`` on one arm, a run on another arm from the
    same directory ended ``stopped: frames may have been lost`` and ``estimate`` changed."""
    estimate_before = armctl("estimate", str(JOB), cwd=tmp_path)
    other_before = armctl("run", str(JOB), "--no-live", "--port", OTHER, cwd=tmp_path)
    probe(tmp_path, "--write", "armctl.toml")
    written = tomllib.loads((tmp_path / "armctl.toml").read_text(encoding="utf-8"))["connector"]
    assert written["measured_on"] == ARM and written["fifo_frames"] == 50

    forget = armctl("probe", "--forget", "--port", PORT, cwd=tmp_path)
    assert forget.returncode == 0 and f"forgot the calibration of {ARM}" in forget.stdout
    run = armctl("run", str(JOB), "--no-live", "--port", PORT, cwd=tmp_path)
    assert run.stdout.splitlines()[-1] == DONE, run.stdout + run.stderr

    other = armctl("run", str(JOB), "--no-live", "--port", OTHER, cwd=tmp_path)
    assert other.returncode == 0 and summary(other) == summary(other_before)
    estimate = armctl("estimate", str(JOB), cwd=tmp_path)  # no port configured: the simulator's arm
    assert estimate.stdout == estimate_before.stdout


def test_estimate_uses_the_configured_ports_calibration_and_says_so(tmp_path):
    probe(tmp_path)
    plain = armctl("estimate", str(JOB), cwd=tmp_path)
    (tmp_path / "armctl.toml").write_text(f'port = "{PORT}"\n')
    calibrated = armctl("estimate", str(JOB), cwd=tmp_path)
    assert calibrated.returncode == 0, calibrated.stderr
    assert calibrated.stdout != plain.stdout
    assert f"  note: the arm's speed_factor 1.3" in calibrated.stdout and f" for {ARM})" in calibrated.stdout


def test_probe_list_and_forget(tmp_path):
    empty = armctl("probe", "--list", cwd=tmp_path)
    assert empty.returncode == 0 and empty.stdout.startswith("no arm probed yet")
    probe(tmp_path)
    listing = armctl("probe", "--list", cwd=tmp_path)
    assert listing.returncode == 0 and listing.stdout.splitlines()[0] == f"{ARM}  (last probed through {PORT})"
    assert "    fifo_frames = 50  (probed on " in listing.stdout
    as_json = json.loads(armctl("probe", "--list", "--json", cwd=tmp_path).stdout)
    assert as_json[ARM]["settings"]["fifo_frames"]["value"] == 50

    forget = armctl("probe", "--forget", ARM, cwd=tmp_path)
    assert forget.returncode == 0, forget.stderr
    again = armctl("probe", "--forget", PORT, cwd=tmp_path)
    assert again.returncode == 1 and f"nothing stored for {ARM}" in again.stderr
    assert armctl("probe", "--list", cwd=tmp_path).stdout.startswith("no arm probed yet")
    both = armctl("probe", "--list", "--forget", cwd=tmp_path)
    assert both.returncode == 2 and "choose --list or --forget" in both.stderr


def test_the_api_uses_the_stored_calibration_of_the_arm_it_opens(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    from armctl import Arm
    with Arm.open(PORT) as arm:
        assert arm.run(JOB).outcome == "finished, unproven"  # the document's FIFO of 200, unproven on this arm
    probe(tmp_path)
    with Arm.open(PORT) as arm:
        assert arm.run(JOB).outcome == "finished"
    with Arm.open(OTHER) as arm:
        assert arm.run(JOB).outcome == "finished"  # its own FIFO holds the document's 200


def test_jog_takes_the_profile_of_the_arm_on_its_port(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    from armctl.jog.command import _setup

    probe(tmp_path)
    assert _setup(None, None, PORT)[2].connector.fifo_frames == 50
    assert _setup(None, None, OTHER)[2].connector.fifo_frames == 200


BENCH = ("bench", "--quick", "--scenario", "fast", "--scenario", "slow", "--scenario", "fifo50", "--jobs", "1")


@pytest.mark.timeout(180)
def test_bench_reads_no_configuration(tmp_path):
    """The issue: from a directory holding a probed armctl.toml, ``bench --quick`` missed a target
    it meets elsewhere (``fast armctl … 1.057 (≤ 1.03)``).  Here the directory's file (a [connector]
    naming no arm, a [profile] of other timings, a port), the user's file and a stored calibration
    of that port all change nothing."""
    probed, empty = tmp_path / "probed", tmp_path / "empty"
    probed.mkdir(), empty.mkdir()
    (probed / "armctl.toml").write_text(
        'port = "sim://?fifo_frames=50&speed_factor=1.3"\n\n[profile.timing]\ncommand_overhead_s = 0.05\n\n'
        '[connector]\nfifo_frames = 50\ncontrol_frames = "queued"\nstatus_xyz_frame = "worktable"\n'
        "speed_factor = 1.301\nkinematics_verified = true\nspeed_tolerance = 1.05\n")
    probe(probed)
    tables = []
    for where in (probed, empty):
        result = armctl(*BENCH, cwd=where)
        tables.append([line for line in result.stdout.splitlines() if "wall time" not in line])
        assert result.returncode == 0, result.stdout + result.stderr
    assert tables[0] == tables[1]
