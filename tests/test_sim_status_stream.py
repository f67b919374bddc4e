"""The simulator's status byte stream, pinned: a job of Cartesian lines, an arc, joint moves,
PWM, a delay and a pause, advanced burst by burst as a virtual-time host does, must give the
very bytes it gave before issue 11's speed work (the joints reported come from IK per frame,
the positions from FK; a cache or a shortcut that changed one value by 0.01° fails here)."""

from __future__ import annotations

import hashlib

from armctl.core.protocol import (
    ArcEnd, ArcStart, Delay, JointMove, LinearMove, PauseToggle, StatusReader,
)
from armctl.sim.model import SimOptions, SimulatedArm

# Recorded on main at b5c823b (before the speed work), by this very test.
EXPECTED_SHA256 = "2b378a36122e06a8b7c8f32d105a41a89f6bdb726c397e80b3955de15e704ce5"
EXPECTED_FRAMES = 2000


def _commands():
    line = dict(b0_deg=180.0, b1_deg=0.0, w_deg=0.0, e0_deg=0.0, e1_deg=0.0)
    yield LinearMove(x_mm=250.0, y_mm=-50.0, z_mm=150.0, pwm_us=1000.0, speed_mm_min=3000.0, pwm_channel=1, **line)
    for k in range(3):
        yield LinearMove(x_mm=250.0 + 10 * k, y_mm=50.0 if k % 2 == 0 else -50.0, z_mm=150.0 - 5 * k, pwm_us=1200.0,
                         speed_mm_min=600.0, pwm_channel=1, **line)
    yield LinearMove(x_mm=230.0, y_mm=20.0, z_mm=170.0, b0_deg=170.0, b1_deg=10.0, w_deg=30.0, pwm_us=1500.0,
                     speed_mm_min=900.0, e0_deg=0.0, e1_deg=0.0, pwm_channel=1)
    yield ArcStart(x_mm=260.0, y_mm=40.0, z_mm=150.0, pwm_us=1500.0, radius_mm=50.0, speed_mm_min=1200.0, **line)
    yield ArcEnd(x_mm=230.0, y_mm=80.0, z_mm=150.0, pwm_us=1500.0, speed_mm_min=1200.0, **line)
    yield Delay(500.0)
    yield JointMove(j1_deg=20.0, j2_deg=10.0, j3_deg=-10.0, j4_deg=5.0, j5_deg=80.0, j6_deg=-20.0, pwm_us=1600.0,
                    speed_deg_s=20.0, e0_deg=0.0, e1_deg=0.0, smoothing=0)
    yield LinearMove(x_mm=240.0, y_mm=0.0, z_mm=160.0, pwm_us=1400.0, speed_mm_min=1500.0, pwm_channel=1, **line)


def status_stream() -> tuple[bytes, int]:
    """The status bytes of the job (frames written 0.1 s apart, a pause toggled twice, acting on arrival), read
    from status burst to status burst until the arm has been idle for a second."""
    arm, reader = SimulatedArm(SimOptions(control_frames="arrival")), StatusReader()
    writes = [(0.1 * k, command.encode()) for k, command in enumerate(_commands())]
    writes += [(3.0, PauseToggle().encode()), (4.5, PauseToggle().encode())]
    out, frames, now_s, k = bytearray(), 0, 0.0, 0
    end_s = 60.0
    while now_s < end_s:
        due_s = min(arm.next_output_time(), end_s)
        while k < len(writes) and writes[k][0] <= due_s:
            arm.write(writes[k][1], writes[k][0])
            k += 1
        now_s = due_s
        data = arm.advance(now_s)
        frames += len(reader.feed(data))
        out += data
    return bytes(out), frames


def test_the_status_stream_of_a_job_is_unchanged():
    data, frames = status_stream()
    assert frames == EXPECTED_FRAMES
    assert hashlib.sha256(data).hexdigest() == EXPECTED_SHA256
