"""What real lines have, on ``sim://`` (issue 21): a bounded write buffer between host and arm,
a coarse read granularity — and the host's write-ahead into such a buffer, which must never
make a frame land before the streamer's model says nor loosen the lead.

Deterministic: virtual clocks, or a fake clock handed to the simulator's real-time wrapper.
"""

from __future__ import annotations

import pytest
import serial

import armctl  # noqa: F401  (registers sim://)
from armctl.host.link import Link
from armctl.core.motion import MotionModel
from armctl.host.profile import load_profile
from armctl.core.protocol import FRAME_SIZE, LinearMove, frame_seconds
from armctl.sim.model import SimOptions, SimulatedArm
from armctl.sim.protocol_sim import SimOptionError, parse_sim_url
from armctl.sim.realtime import RealtimeArm
from armctl.core.streamer import Streamer, WaitReason


def test_the_two_options_parse_with_their_units_and_ranges():
    options = parse_sim_url("sim://?write_buffer_bytes=4096&read_granularity_ms=16")
    assert options.write_buffer_bytes == 4096 and options.read_granularity_s == pytest.approx(0.016)
    assert parse_sim_url("sim://").write_buffer_bytes is None and parse_sim_url("sim://").read_granularity_s == 0.0


@pytest.mark.parametrize("url, words", [
    ("sim://?write_buffer_bytes=47", "write_buffer_bytes must be a whole number 48…1048576"),
    ("sim://?write_buffer_bytes=4k", "write_buffer_bytes must be a whole number"),
    ("sim://?read_granularity_ms=101", "read_granularity_ms must be a number 0…100"),
    ("sim://?read_granularity_ms=nan", "read_granularity_ms must be a number"),
    ("sim://?clock=virtual&read_granularity_ms=16", "read_granularity_ms has no meaning with clock=virtual"),
])
def test_bad_values_are_refused_naming_the_option(url, words):
    with pytest.raises(SimOptionError, match=words):
        parse_sim_url(url)


def test_a_full_write_buffer_blocks_the_write_until_the_line_took_enough():
    with serial.serial_for_url("sim://?clock=virtual&write_buffer_bytes=96", baudrate=9600) as port:
        assert port.write(bytes(5 * FRAME_SIZE)) == 5 * FRAME_SIZE
        # 240 bytes through 96 of buffer: the write returns once 144 have left (3 frames' time)
        assert port.virtual_clock.now_s == pytest.approx(3 * frame_seconds(9600))
        assert port.out_waiting == 96


def test_without_a_buffer_a_write_never_blocks():
    with serial.serial_for_url("sim://?clock=virtual", baudrate=9600) as port:
        port.write(bytes(50 * FRAME_SIZE))
        assert port.virtual_clock.now_s == 0.0 and port.out_waiting == 50 * FRAME_SIZE


def test_a_write_that_cannot_finish_in_its_write_timeout_raises_as_pyserial_ports_do():
    with serial.serial_for_url("sim://?write_buffer_bytes=96", baudrate=9600, write_timeout=0.01) as port:
        with pytest.raises(serial.SerialTimeoutException):
            port.write(bytes(5 * FRAME_SIZE))


def test_status_bytes_reach_the_host_only_at_the_read_ticks():
    wall = [0.0]
    arm = RealtimeArm(SimulatedArm(SimOptions(read_granularity_s=0.016)), clock=lambda: wall[0])
    got = []
    for step in range(1, 200):  # every millisecond for 0.2 s
        wall[0] = step / 1000
        if arm.poll():
            got.append(step)
    assert got and all(ms % 16 == 0 for ms in got)
    # the sleep it asks for ends on a tick too
    wall[0] = 0.2005
    wake_ms = (wall[0] + arm.wall_seconds_until_output()) * 1000
    assert wake_ms == pytest.approx(round(wake_ms)) and round(wake_ms) % 16 == 0


def test_the_bridge_reads_the_host_only_while_the_write_buffer_has_room():
    from armctl.sim.bridge import _take_room

    wall = [0.0]
    arm = RealtimeArm(SimulatedArm(SimOptions(write_buffer_bytes=96)), clock=lambda: wall[0])
    assert _take_room(arm) == 96
    arm.write(bytes(96))
    assert _take_room(arm) == 0
    wall[0] = frame_seconds(9600) + 1e-6
    assert _take_room(arm) == FRAME_SIZE


def _streamer(write_ahead_s: float, lead_s: float = 2.0) -> Streamer:
    model = MotionModel(load_profile())
    return Streamer(model, model.initial_pose(), lead_s=lead_s, write_ahead_s=write_ahead_s)


def _tiny(x_mm: float) -> LinearMove:
    return LinearMove(x_mm, 0.0, 250.0, 180.0, 0.0, 0.0, 1500.0, 6000.0)


def test_a_frame_written_ahead_starts_when_the_line_is_free_so_it_lands_when_the_model_says():
    streamer = _streamer(write_ahead_s=0.02)
    first = streamer.wrote(_tiny(250.0), 0.0)
    second = streamer.wrote(_tiny(251.0), first.wire_end_s)  # the first has landed and begun
    when = streamer.next_write_time(first.wire_end_s, _tiny(250.0))
    assert when == pytest.approx(second.wire_end_s - 0.02)
    assert streamer.write_reason is WaitReason.WIRE
    third = streamer.wrote(_tiny(250.0), when)
    assert third.wire_end_s == pytest.approx(second.wire_end_s + streamer.frame_s)


def test_behind_a_first_frame_still_on_the_wire_the_lead_waits_for_it_to_begin():
    """Written ahead while the first frame is still on the wire, a second frame that fits in the
    lead only behind a first one in progress would leave both to run after a stop asked then
    (the real-time bench: 3.43 s after a stop against 2.0 s, 6 long moves at 9600 baud)."""
    streamer = _streamer(write_ahead_s=0.05)
    first = streamer.wrote(LinearMove(250.0, 0.0, 250.0, 180.0, 0.0, 0.0, 1500.0, 6000.0), 0.0)
    nxt = LinearMove(250.0, 100.0, 250.0, 180.0, 0.0, 0.0, 1500.0, 6000.0)  # 1 s
    assert streamer.next_write_time(0.0, nxt) == pytest.approx(first.wire_end_s)


def test_write_ahead_never_lets_a_frame_past_the_lead():
    ahead, plain = _streamer(write_ahead_s=0.05, lead_s=0.5), _streamer(write_ahead_s=0.0, lead_s=0.5)
    for streamer in (ahead, plain):
        streamer.wrote(LinearMove(250.0, 0.0, 250.0, 180.0, 0.0, 0.0, 1500.0, 600.0), 0.0)  # a long move
        streamer.wrote(LinearMove(250.0, 20.0, 250.0, 180.0, 0.0, 0.0, 1500.0, 600.0), 0.0)  # 2 s behind it
    nxt = LinearMove(250.0, 30.0, 250.0, 180.0, 0.0, 0.0, 1500.0, 600.0)
    assert ahead.next_write_time(0.06, nxt) == plain.next_write_time(0.06, nxt) > 0.5
    assert ahead.write_reason is WaitReason.LEAD


def test_what_the_port_still_holds_pushes_the_next_start_back():
    with Link.open("sim://?clock=virtual", 9600) as link:
        link.write(bytes(2 * FRAME_SIZE))
        assert link.unsent_s() == pytest.approx(2 * frame_seconds(9600))
    streamer = _streamer(write_ahead_s=0.0)
    streamer.line_busy_until(0.1)
    assert streamer.wrote(_tiny(250.0), 0.0).wire_end_s == pytest.approx(0.1 + streamer.frame_s)
