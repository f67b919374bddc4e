"""``sim://?clock=virtual``: the simulator on a clock that moves only while armctl waits.

What must hold: the port never blocks; ``Link`` reads each status frame at the model time it
lands (so a log shows the same times as the model); a whole ``armctl run`` gives the same bytes
at the same times every time, on any machine; commands that need time to pass by itself refuse
a virtual clock with a sentence and exit 2.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import serial
from click.testing import CliRunner

import armctl  # noqa: F401  (registers sim://)
from armctl.ui.cli import main
from armctl.host.link import Link
from armctl.core.protocol import STATUS_SIZE, Delay, StatusReader
from armctl.sim.protocol_sim import parse_sim_url
from armctl.sim.realtime import VirtualClock

TIMED = Path(__file__).resolve().parent / "data" / "scripts_cli" / "timed_job.txt"

VIRTUAL = "sim://?clock=virtual"


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)


def test_the_clock_only_moves_forward_when_told():
    clock = VirtualClock()
    assert clock() == 0.0
    clock.advance_to(1.5)
    clock.advance_to(1.0)  # never back
    assert clock() == 1.5


def test_url_option_parses_and_refuses_a_speed_with_it():
    assert parse_sim_url(VIRTUAL).virtual_clock and not parse_sim_url("sim://?speed=4").virtual_clock
    assert parse_sim_url("sim://?clock=wall").time_scale == 1.0
    with pytest.raises(serial.SerialException, match="speed has no meaning with clock=virtual"):
        serial.serial_for_url("sim://?clock=virtual&speed=4")
    with pytest.raises(serial.SerialException, match="clock must be 'wall' or 'virtual'"):
        serial.serial_for_url("sim://?clock=fast")


def test_a_virtual_port_never_blocks_and_time_stands_still_until_advanced():
    with serial.serial_for_url(VIRTUAL, timeout=None) as port:  # timeout=None would block forever on a wall clock
        assert port.read(100) == b""
        assert port.next_output_s() == pytest.approx(STATUS_SIZE * 10 / 9600)
        port.virtual_clock.advance_to(1.0)
        received = port.read(10_000)
        frames = StatusReader().feed(received)
        assert len(frames) == 34  # one every 30 ms from t = 0 (t = 0.99 s lands at 0.999 s)
        assert port.read(10) == b""


def test_flush_moves_the_clock_to_when_the_last_byte_has_landed():
    with serial.serial_for_url(VIRTUAL) as port:
        port.write(Delay(10).encode() * 3)
        port.flush()
        assert port.virtual_clock() == pytest.approx(3 * 48 * 10 / 9600)
        assert port.out_waiting == 0


def test_link_reads_each_status_frame_at_the_model_time_it_lands():
    times = []
    link = Link.open(VIRTUAL, on_status=lambda frame, at_s: times.append(at_s))
    with link:
        assert link.is_virtual and not link._thread.is_alive()
        link.idle(0.5)
        assert times == [pytest.approx(STATUS_SIZE * 10 / 9600)]  # idle returns once a frame has been read
        assert link.wait_until(lambda state: state.frames >= 10, timeout_s=5.0)
        burst_s = STATUS_SIZE * 10 / 9600
        assert times == pytest.approx([k * 0.030 + burst_s for k in range(10)])
        start_s = link.clock()
        assert start_s == times[-1]
        assert not link.wait_until(lambda state: False, timeout_s=0.25)  # times out in model time
        assert link.clock() == pytest.approx(start_s + 0.25)


def test_a_tiny_wait_still_moves_the_clock():
    # A caller that waits for ``when - now`` where both are nearly equal must not spin forever.
    with Link.open(VIRTUAL) as link:
        before = link.clock()
        link.idle(1e-18)
        assert link.clock() > before


def _run_log(tmp_path, name: str) -> list[dict]:
    log = tmp_path / name
    result = CliRunner().invoke(main, ["run", str(TIMED), "--port", VIRTUAL, "--no-live", "--log", str(log)])
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"
    return [json.loads(line) for line in log.read_text().splitlines()]


def test_a_whole_run_is_the_same_bytes_at_the_same_times_every_time(tmp_path):
    first, second = _run_log(tmp_path, "a.log"), _run_log(tmp_path, "b.log")
    assert first == second
    sent = [r for r in first if r["dir"] == "tx"]
    assert len(sent) == 14
    assert all(b["t"] - a["t"] >= 0.05 - 1e-9 for a, b in zip(sent, sent[1:]))  # never faster than the line


@pytest.mark.parametrize(
    "args, says",
    [
        (["status", "--watch", "--port", VIRTUAL], "status --watch runs in real time"),
        (["sim", "--pty", "--url", VIRTUAL], "a served simulator runs in real time"),
    ],
)
def test_commands_that_need_a_moving_clock_refuse_a_virtual_one(args, says):
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2
    assert says in result.stderr
    assert "Traceback" not in result.output


@pytest.mark.realtime
def test_idle_on_a_wall_clock_port_returns_after_a_status_frame_or_the_time():
    with Link.open("sim://?speed=10") as link:
        link.wait_until(lambda state: state.frames >= 1, timeout_s=5.0)
        frames = link.snapshot()[3]
        link.idle(10.0)  # 10 s of model time = 1 s of wall time; a frame comes every 30 ms
        assert link.snapshot()[3] > frames
    with Link.open("loop://") as silent:
        before = silent.clock()
        silent.idle(0.05)
        assert silent.clock() - before >= 0.05


@pytest.mark.parametrize("faults", ["loss=0.3", "corrupt=0.2", "noise=0.5"])
def test_a_virtual_run_with_faulty_status_still_finishes(faults):
    result = CliRunner().invoke(main, ["run", str(TIMED), "--port", f"{VIRTUAL}&{faults}&seed=3", "--no-live"])
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"


def test_a_virtual_arm_that_says_nothing_times_out_in_model_time():
    result = CliRunner().invoke(main, ["run", str(TIMED), "--port", f"{VIRTUAL}&loss=1", "--no-live"])
    assert result.exit_code == 1
    assert "no complete status from sim://?clock=virtual&loss=1 at 9600 baud within 3 s: received nothing" in result.stderr
    assert "Traceback" not in result.output


def test_the_virtual_clock_keeps_moving_at_large_model_times(tmp_path):
    # At 4 Mbaud float rounding once left a status burst "due now" but not yet handed over
    # after 1024 s of model time, and the clock stalled for ever.
    job = tmp_path / "long.txt"
    job.write_text("G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\n" + "G4 P60000\n" * 20 + "G1 X250 Y50 Z150\n")
    result = CliRunner().invoke(main, ["run", str(job), "--port", f"{VIRTUAL}&baud=4000000", "--baud", "4000000",
                                       "--no-live"])
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[-1] == "finished: the arm finished the job"


def test_status_that_always_looks_like_motion_does_not_keep_run_waiting_for_ever():
    # Every status frame corrupted: the readings jump about, which looks like an arm at work — since
    # a job waits for a moving arm to come to rest (jobflow.read_arm), within a bound, then sends nothing.
    result = CliRunner().invoke(main, ["run", str(TIMED), "--port", f"{VIRTUAL}&corrupt=1", "--no-live"])
    assert result.exit_code == 1, result.output
    assert "a line so noisy every report differs" in result.stderr
    assert "did not come to rest" in result.stderr and "nothing was sent" in result.stderr
