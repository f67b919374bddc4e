"""Control of a running job through the Python API: ``Arm.pause``, ``resume``, ``feed_override``.

Strategy: each call is a request to the job engine (armctl/core/job.py, via ``JobRunner.control``),
so these tests drive a job through ``Arm.run`` on a simulator in virtual time, in both
control-frame modes (H5: ``sim://?clock=virtual&control_frames=queued|arrival``), and judge it
by the simulated arm's own record: what it took and when (``execution_log``, model time) and
the frames it received (``frames_received``) — never by what armctl believes it sent.
"""

from __future__ import annotations

import threading

import pytest

from armctl import Arm, ArmctlError
from armctl.core.protocol import LinearMove, PauseToggle

MODES = ["queued", "arrival"]
SPEED_MM_MIN = 1200.0


def port(control_frames: str) -> str:
    return f"sim://?clock=virtual&control_frames={control_frames}"


def zigzag(arm: Arm, moves: int = 12) -> str:
    """A job of ``moves`` short G1 moves at one speed (about a second each), from where the arm is."""
    x, y, z = arm.status().position_mm
    lines = [f"G1 X{x + 20 * (k % 2):.1f} Y{y + 2 * k:.1f} Z{z:.1f} F{SPEED_MM_MIN:g}" for k in range(1, moves + 1)]
    lines[0] += " A180 B0 C0 S1500"  # the first move sets what the others keep
    return "".join(line + "\n" for line in lines)


def model_of(arm: Arm):
    return arm._link.port.model


def taken(arm: Arm) -> list:
    """(start_s, command) of every frame the simulated arm took or acted on, in model time."""
    return [(e.start_s, e.command) for e in model_of(arm).execution_log]


def received_moves(arm: Arm) -> list[LinearMove]:
    return [f.command for f in model_of(arm).frames_received if isinstance(f.command, LinearMove)]


@pytest.mark.parametrize("control_frames", MODES)
def test_pause_holds_the_arm_and_resume_finishes_the_job(control_frames):
    events = {}

    def on_progress(progress):
        if progress.frames_sent >= 3 and "pause" not in events:
            events["pause"] = arm.pause()
        elif progress.paused and "paused_s" not in events:
            events["paused_s"] = progress.elapsed_s
        elif "paused_s" in events and "resume" not in events and progress.elapsed_s - events["paused_s"] >= 3.0:
            events["resume"] = arm.resume()

    with Arm.open(port=port(control_frames)) as arm:
        job = zigzag(arm)
        result = arm.run(job, on_progress=on_progress, timeout=60)
        assert (events["pause"], events["resume"]) == (True, True)
        assert result.finished and result.frames_sent == result.total_frames == 12
        record = taken(arm)
        toggles_s = [t for t, command in record if isinstance(command, PauseToggle)]
        assert len(toggles_s) == 2
        paused_s, resumed_s = toggles_s
        assert resumed_s - paused_s >= 2.5  # the arm really was held (3 s of the job's clock, less a report)
        moves_s = [t for t, command in record if isinstance(command, LinearMove)]
        assert not [t for t in moves_s if paused_s < t < resumed_s]  # the arm took nothing while paused
        arrived = [f.command for f in model_of(arm).frames_received]
        first = arrived.index(PauseToggle())
        # and nothing was written between the toggles: the engine held the feed (in the queued
        # mode a frame after the pause would keep the arm paused for good; in the arrival mode
        # the streamer's clock stops too while the arm reports paused)
        assert arrived[first + 1] == PauseToggle()
        assert len(moves_s) == 12 and received_moves(arm) == [c for _, c in record if isinstance(c, LinearMove)]
        assert model_of(arm).frames_dropped == 0


@pytest.mark.parametrize("control_frames", MODES)
def test_pause_and_resume_from_another_thread(control_frames):
    """From a thread that is not the arm's worker, each call waits for the engine's answer."""
    answers: list = []
    asked = threading.Event()

    def ask(method) -> None:
        threading.Thread(target=lambda: (answers.append((method.__name__, method())), asked.set())).start()

    def on_progress(progress):
        if progress.frames_sent >= 3 and not answers and not asked.is_set():
            asked.set()
            ask(arm.pause)
        elif progress.paused and answers == [("pause", True)] and asked.is_set():
            asked.clear()
            ask(arm.resume)

    with Arm.open(port=port(control_frames)) as arm:
        result = arm.run(zigzag(arm), on_progress=on_progress, timeout=60)
        assert asked.wait(10)
        assert answers == [("pause", True), ("resume", True)]
        assert result.finished and len(received_moves(arm)) == 12


@pytest.mark.parametrize("control_frames", MODES)
def test_a_feed_override_changes_the_speed_of_the_frames_written_after_it(control_frames):
    seen = {}

    def on_progress(progress):
        if progress.frames_sent >= 4 and "percent" not in seen:
            seen["written"] = progress.frames_sent
            seen["percent"] = arm.feed_override(150)

    with Arm.open(port=port(control_frames)) as arm:
        result = arm.run(zigzag(arm), on_progress=on_progress, timeout=60)
        assert result.finished and seen["percent"] == 150
        speeds = [move.speed_mm_min for move in received_moves(arm)]
        written = seen["written"]
        assert speeds[:written] == [SPEED_MM_MIN] * written
        assert speeds[written:] == [SPEED_MM_MIN * 1.5] * (12 - written)
        assert arm.run(zigzag(arm, 2)).finished  # the override lasted for that job only
        assert [move.speed_mm_min for move in received_moves(arm)][-2:] == [SPEED_MM_MIN] * 2


def test_feed_override_follows_the_engine_grid_and_needs_a_running_job():
    answers = []

    def on_progress(progress):
        if not answers:
            answers.extend(arm.feed_override(p) for p in (500, 3, 154, 100))

    with Arm.open(port=port("queued")) as arm:
        with pytest.raises(ArmctlError, match="no job is running"):
            arm.feed_override(120)
        with pytest.raises(TypeError):
            arm.feed_override("fast")
        assert arm.run(zigzag(arm, 2), on_progress=on_progress, timeout=60).finished
        assert answers == [200, 10, 150, 100]
