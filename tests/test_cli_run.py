"""``armctl run`` and ``armctl estimate`` as a user sees them, end to end.

Jobs stream through ``CliRunner`` to the simulator at ``sim://?clock=virtual`` (model time moves
only while armctl waits on the port, so half a minute of arm time takes a fraction of a second
and every figure is the same on any machine, however loaded), to the simulator's
TCP and pty bridges running in a thread (stopped mid-job for a lost port), and — in real time,
with a job of under a second of arm time — to ``armctl sim --pty`` started as a separate process.
Ctrl-C is a real SIGINT to a subprocess.

Fixtures (tests/data/scripts_cli/): short_job.txt (5 frames, < 1 s of arm time), timed_job.txt
(a pick and place, about 30 s of arm time), resume_job.txt, compile_error_job.txt, lint_error_job.txt.
"""

from __future__ import annotations

import contextlib
import json
import os
import queue
import re
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from click.testing import CliRunner

import armctl.host.link
from armctl.ui.cli import main
from armctl.sim.bridge import serve_pty, serve_tcp
from armctl.sim.model import SimOptions, SimulatedArm

SCRIPTS = Path(__file__).resolve().parent / "data" / "scripts_cli"
SHORT = SCRIPTS / "short_job.txt"
TIMED = SCRIPTS / "timed_job.txt"
RESUME = SCRIPTS / "resume_job.txt"  # lint-clean; an arc on lines 5-6, a repeat block on lines 7-9
FAST_SIM = "sim://?clock=virtual"
ARMCTL = [sys.executable, "-m", "armctl"]


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)


def run(*args):
    return CliRunner().invoke(main, ["run", *map(str, args)])


def compiled_frames(script: Path) -> list[dict]:
    result = CliRunner().invoke(main, ["compile", str(script), "--format", "json"])
    assert result.exit_code == 0, result.output
    return [json.loads(line) for line in result.stdout.splitlines()]


def read_log(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


@pytest.fixture
def recorded_writes(monkeypatch):
    """Every frame any Link writes, and every port opened."""
    writes: list[bytes] = []
    opened: list[str] = []
    real_write, real_open = armctl.host.link.Link.write, armctl.host.link.open_port

    def write(self, frame):
        writes.append(bytes(frame))
        return real_write(self, frame)

    def open_port(url, *args, **kwargs):
        opened.append(url)
        return real_open(url, *args, **kwargs)

    monkeypatch.setattr(armctl.host.link.Link, "write", write)
    monkeypatch.setattr(armctl.host.link, "open_port", open_port)
    return writes, opened


SUMMARY_STOPPED = re.compile(
    r"^last line sent: (?P<sent>\d+|none)\nlast line known executed: (?P<done>\d+|none)\n"
    r"resume with: armctl run (?P<script>\S+) --from-line (?P<resume>\d+)",
    re.M,
)


# --- a job that finishes ------------------------------------------------------------------------


def test_a_small_job_streams_and_finishes_with_a_summary(recorded_writes):
    writes, opened = recorded_writes
    result = run(SHORT, "--port", FAST_SIM, "--no-live")
    assert result.exit_code == 0, result.output
    assert result.stderr.splitlines()[0] == f"armctl: using the built-in simulator ({FAST_SIM})"
    lines = result.stdout.splitlines()
    assert "frames: 5 of 5 sent" in lines
    assert lines[-1] == "finished: the arm finished the job"
    assert any(line.startswith("arm time: ") for line in lines)
    assert opened == [FAST_SIM]
    assert [frame.hex() for frame in writes] == [record["hex"] for record in compiled_frames(SHORT)]
    assert "Traceback" not in result.output


def test_the_log_holds_tx_and_rx_records_and_the_arm_time_agrees_with_estimate(tmp_path):
    log = tmp_path / "timed.log"
    result = run(TIMED, "--port", FAST_SIM, "--no-live", "--log", log)
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"

    # the arm time the run measured against `armctl estimate` of the same job (both start at pose 0)
    measured = re.search(r"^arm time: ([\d.]+) s from the first frame to the arm at rest", result.stdout, re.M)
    assert measured, result.stdout
    estimate = CliRunner().invoke(main, ["estimate", str(TIMED), "--json"])
    assert estimate.exit_code == 0, estimate.output
    job_s = json.loads(estimate.stdout)["job_s"]
    assert 20 < job_s < 40
    assert abs(float(measured.group(1)) / job_s - 1) <= 0.05

    # the log: every frame written (in order, with its line) and the status frames read
    records = read_log(log)
    assert {r["dir"] for r in records} == {"job", "tx", "rx", "progress"}  # job, progress: armctl/core/joblog.py
    assert records[0]["dir"] == "job"
    records = [r for r in records if r["dir"] in ("tx", "rx")]
    assert all(set(r) >= {"t", "dir", "hex"} for r in records)
    sent = [r for r in records if r["dir"] == "tx"]
    frames = compiled_frames(TIMED)
    assert [(r["line"], r["hex"]) for r in sent] == [(f["source"]["line"], f["hex"]) for f in frames]
    assert [r["t"] for r in sent] == sorted(r["t"] for r in sent)
    received = [r for r in records if r["dir"] == "rx"]
    assert all(len(bytes.fromhex(r["hex"])) == 9 and r["kind"] == bytes.fromhex(r["hex"])[7] for r in received)
    assert len(received) > 100  # ~30 s of status frames, one every 30 ms (some before the first tx are not logged)

    decoded = CliRunner().invoke(main, ["decode", str(log)])
    assert decoded.exit_code == 0
    assert f"{len(sent)} command frame(s), {len(received)} status frame(s), 0 invalid frame(s), 0 byte(s) in no frame" \
        in decoded.stderr


def test_estimate_prints_time_frames_path_shares_and_peak_queue():
    result = CliRunner().invoke(main, ["estimate", str(TIMED)])
    assert result.exit_code == 0, result.output
    text = result.stdout
    for row in ("frames            14", "job time", "line-bound share", "arm-bound share", "path", "peak queue"):
        assert row in text, row
    as_json = json.loads(CliRunner().invoke(main, ["estimate", str(TIMED), "--json"]).stdout)
    assert as_json["frames"] == 14
    assert as_json["line_bound_share"] + as_json["arm_bound_share"] == pytest.approx(1.0)
    assert as_json["path_mm"] > 0


# --- nothing is sent when the script is wrong ------------------------------------------------


def test_a_script_with_a_compile_error_sends_nothing(tmp_path, recorded_writes):
    writes, opened = recorded_writes
    log = tmp_path / "never.log"
    result = run(SCRIPTS / "compile_error_job.txt", "--port", FAST_SIM, "--log", log, "--no-live")
    assert result.exit_code == 1
    assert f"{SCRIPTS / 'compile_error_job.txt'}:3:5: E001 expected a number after Z" in result.stderr
    assert "nothing was sent to the arm" in result.stderr
    assert writes == [] and opened == []
    assert not log.exists()
    assert result.stdout == ""


def test_a_script_with_a_lint_error_sends_nothing(tmp_path, recorded_writes):
    writes, opened = recorded_writes
    # the user's own profile (the packaged numbers, given as the user's): its workspace is an error,
    # the built-in profile's illustrative one only a warning (tests/test_lint_provenance.py)
    from importlib import resources

    measured = tmp_path / "measured.toml"
    measured.write_bytes(resources.files("armctl.data").joinpath("default_profile.toml").read_bytes())
    result = run(SCRIPTS / "lint_error_job.txt", "--port", FAST_SIM, "--no-live", "--profile", measured)
    assert writes == [] and opened == []
    assert result.exit_code == 1
    assert f"{SCRIPTS / 'lint_error_job.txt'}:4:4: L103 " in result.stderr
    assert "nothing was sent to the arm" in result.stderr


@pytest.mark.parametrize("line", [6, 8, 500], ids=["inside-arc", "inside-repeat", "past-the-end"])
def test_a_from_line_the_compiler_rejects_sends_nothing(line):
    result = run(RESUME, "--from-line", line, "--dry-run")
    assert result.exit_code == 1
    assert f"E010 cannot resume at line {line}" in result.stderr


def test_run_reads_stdin_once_like_a_file():
    # the script is read once into a snapshot, so stdin works as well as a file
    result = CliRunner().invoke(main, ["run", "-", "--dry-run"], input="G4 P10\n")
    assert result.exit_code == 0, result.output
    assert "ee3600" in result.stdout and "frames            1" in result.stdout


def test_a_port_that_says_nothing_stops_before_sending(recorded_writes):
    writes, _ = recorded_writes
    result = run(SHORT, "--port", "loop://", "--timeout", "0.2", "--no-live")
    assert result.exit_code == 1
    assert result.stderr.strip() == (
        "armctl: no complete status from loop:// at 9600 baud within 0.2 s: received nothing (is the arm powered and "
        "the cable on the host connector?); nothing was sent"
    )
    assert writes == []


# --- --dry-run and --from-line ------------------------------------------------------------------


def test_dry_run_prints_the_frames_and_the_estimate_and_opens_no_port(monkeypatch):
    def no_port(*args, **kwargs):
        raise AssertionError("--dry-run opened a port")

    monkeypatch.setattr(armctl.host.link, "open_port", no_port)
    monkeypatch.setattr(armctl.host.link.Link, "open", no_port)
    result = run(SHORT, "--dry-run")
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    frames = compiled_frames(SHORT)
    for line, frame in zip(lines, frames):
        number, hex_digits, description = re.fullmatch(r" *(\d+)  ([0-9a-f]{96})  (.+)", line).groups()
        assert (int(number), hex_digits) == (frame["source"]["line"], frame["hex"])
        assert description.startswith(frame["name"])
    assert lines[len(frames)].startswith("dry run: no port opened")
    assert "  frames            5" in lines
    assert any(line.startswith("  job time ") for line in lines)
    assert "simulator" not in result.stderr


def test_from_line_starts_there_with_the_modal_state_before_it(tmp_path):
    # line 10 of timed_job.txt is "G1 Z150 F3000": X250 Y-120, A180 B0 C0 and S2000 come from lines 4 and 7
    log = tmp_path / "resumed.log"
    result = run(TIMED, "--port", FAST_SIM, "--from-line", 10, "--log", log, "--no-live")
    assert result.exit_code == 0, result.output
    sent = [r for r in read_log(log) if r["dir"] == "tx"]
    whole_job = {f["source"]["line"]: f for f in compiled_frames(TIMED)}
    assert sent[0]["line"] == 10
    assert sent[0]["hex"] == whole_job[10]["hex"]
    assert whole_job[10]["fields"]["pwm_us"] == 2000 and whole_job[10]["fields"]["x_mm"] == 250
    assert [r["line"] for r in sent] == [line for line in whole_job if line >= 10]
    assert "frames: 8 of 8 sent" in result.stdout


# --- stopping mid-job: Ctrl-C and a lost port ---------------------------------------------------


def start_job(script: Path, *options: str) -> subprocess.Popen:
    return subprocess.Popen(
        [*ARMCTL, "run", str(script), "--no-live", *options],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env={k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"},
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # background jobs may ignore SIGINT
    )


@pytest.fixture(scope="module")
def interrupted(tmp_path_factory):
    """timed_job.txt at sim://?speed=4, interrupted while the arm is on its first move (about 1 s
    of wall time): SIGINT a moment after the first progress line, which is printed when the first
    frame is written.  (Ctrl-C landing while a write is being recorded: see the in-process test.)"""
    log = tmp_path_factory.mktemp("ctrl-c") / "job.log"
    process = start_job(TIMED, "--port", "sim://?speed=4", "--log", str(log))
    try:
        first = process.stdout.readline()
        threading.Event().wait(0.3)  # not waiting for behaviour: choosing a moment mid-move
        process.send_signal(signal.SIGINT)
        rest, err = process.communicate(timeout=20)
    finally:
        process.kill()
    return process.returncode, first + rest, err, log


@pytest.mark.realtime
def test_ctrl_c_exits_130_and_says_where_to_resume(interrupted):
    code, out, err, log = interrupted
    assert code == 130, err
    match = SUMMARY_STOPPED.search(out)
    assert match, out
    assert match["script"] == str(TIMED)
    sent = [r for r in read_log(log) if r["dir"] == "tx" and r["hex"].startswith("ee")]
    assert match["sent"] == str(sent[-1]["line"])  # the last line sent is the last motion frame logged
    resume = int(match["resume"])
    assert 4 <= resume <= sent[-1]["line"] + 1
    if match["done"] != "none":
        assert int(match["done"]) <= int(match["sent"])
    assert "interrupted" in err and "Traceback" not in err
    assert "frames: " in out and " of 14 sent" in out


@pytest.mark.realtime
def test_the_resume_line_ctrl_c_printed_is_one_the_compiler_accepts(interrupted):
    from armctl.script import compile_file

    resume = int(SUMMARY_STOPPED.search(interrupted[1])["resume"])
    assert compile_file(TIMED, from_line=resume).finish() == []


def test_ctrl_c_during_the_progress_update_never_says_to_resend_a_line_known_executed(monkeypatch):
    from armctl.ui import run_job

    real_update = run_job._Display.update
    pressed = []

    def update(self, view):
        real_update(self, view)
        if view.frames_sent == 1 and not pressed:
            pressed.append(view.last_sent.line)
            raise KeyboardInterrupt

    monkeypatch.setattr(run_job._Display, "update", update)
    result = run(SHORT, "--port", FAST_SIM, "--no-live")
    assert result.exit_code == 130, result.output
    match = SUMMARY_STOPPED.search(result.stdout)
    assert match, result.stdout
    assert (match["sent"], match["done"]) == ("2", "2")
    assert int(match["resume"]) == 3


@pytest.mark.realtime
def test_the_log_holds_the_abort_frame_ctrl_c_sent(interrupted):
    sent = [r for r in read_log(interrupted[3]) if r["dir"] == "tx"]
    assert sent[-1]["hex"].startswith("fc1e0302")  # control 30/3, a[3] = 2: the pause toggle


@contextlib.contextmanager
def bridge_lost_after_first_frame(serve, *args):
    """The simulator behind ``serve`` (real time) in a thread; it stops as soon as the arm has
    received its first frame, as if the cable were pulled."""
    model = SimulatedArm(SimOptions())
    ready: queue.Queue = queue.Queue()
    stop = threading.Event()
    thread = threading.Thread(
        target=lambda: serve(*args, SimOptions(), ready.put, stop=stop, time_scale=1.0, model=model), daemon=True,
    )

    def pull_the_cable():
        while not stop.is_set() and not model.frames_received:
            stop.wait(0.005)
        stop.set()

    thread.start()
    puller = threading.Thread(target=pull_the_cable, daemon=True)
    puller.start()
    try:
        yield ready.get(timeout=5.0)
    finally:
        stop.set()
        thread.join(2.0)
        puller.join(2.0)


@pytest.mark.parametrize("serve, args", [(serve_tcp, (0,)), (serve_pty, ())], ids=["tcp", "pty"])
def test_a_port_lost_mid_job_exits_1_with_the_summary(serve, args):
    with bridge_lost_after_first_frame(serve, *args) as where:
        result = run(TIMED, "--port", where, "--no-live")
    assert result.exit_code == 1, result.output
    assert isinstance(result.exception, SystemExit)
    match = SUMMARY_STOPPED.search(result.stdout)
    assert match, result.stdout
    assert match["sent"] != "none"
    assert re.search(rf"^note: the port {re.escape(where)} went away", result.stderr, re.M)
    assert result.stderr.splitlines()[-1] == "stopped: port lost"
    assert "Traceback" not in result.output


# --- against `armctl sim --pty` in another process, in real time --------------------------------


@pytest.mark.realtime
def test_a_small_job_through_armctl_sim_pty_in_another_process(sim_pty):
    result = run(SHORT, "--port", sim_pty, "--no-live")
    # a device path with the document's FIFO size, not probed: the frames confirmed by time
    # alone could have been dropped, so the run does not say done (exit 1)
    assert result.exit_code == 1, result.output
    assert "frames: 5 of 5 sent" in result.stdout
    assert result.stdout.splitlines()[-1].startswith("finished, unproven:")
    assert "run `armctl probe` once" in result.stdout
    assert "simulator" not in result.stderr  # a real device path: no simulator banner
