"""Issue 9 item 3: an abort and its printed resume command, run against ONE simulated arm kept
across the two ``armctl run``s, execute every line of the job exactly once — in both control
modes (``control_frames`` queued = H5, or arrival) and both abort sequences (pause,
reset-connector).  Virtual time.

One arm across two runs: ``armctl.host.link.open_port`` is wrapped so the second open of the same
``sim://`` URL returns the same port (reopened: the simulated arm, its FIFO, its pause state and
its virtual clock carry on), the way the same cable reaches the same arm.

Exactly once, read from the simulator's execution log: the targets of the motion frames the arm
finished, in order, are the job's targets, each once — the only repeat allowed is the same
absolute target twice in a row: the frame a pause froze, re-sent by the resume, is a move to
where the arm already is (idempotent; a relative move or an arc would not be, and the compiler
sends neither as such: every frame carries its absolute target).
"""

from __future__ import annotations

import re
import shlex

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armctl.host.link
import armctl.host.runner
from armctl.ui.cli import main
from armctl.core.protocol import JointMove, LinearMove, PauseToggle, ResetConnector
from armctl.sim.executor import DONE

STOP_AFTER_FRAMES = 14


def _job() -> str:
    """A start pose, then 30 moves of 0.5 s, each to a target of its own."""
    lines = ["G1 X200 Y0 Z250 A180 B0 C0 S1500 F3000"]
    lines += [f"G1 X{200 + 5 * (k + 1)} Y{(k % 5) * 4} Z250 F600" for k in range(30)]
    return "\n".join(lines) + "\n"


@pytest.fixture
def one_arm(tmp_path, monkeypatch):
    """``armctl run`` twice on the same simulated arm: (invoke(args) → result, the ports opened)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    (tmp_path / "job.txt").write_text(_job(), encoding="utf-8")
    return _open_one_arm(monkeypatch)


def _open_one_arm(monkeypatch) -> dict:
    ports: dict = {}
    real_open = armctl.host.link.open_port

    def open_port(url, *args, **kwargs):
        port = ports.get(url)
        if port is None:
            port = ports[url] = real_open(url, *args, **kwargs)
        else:
            port.is_open = True  # the same arm, still where the first run left it
        return port

    monkeypatch.setattr(armctl.host.link, "open_port", open_port)
    return ports


def _stop_after(monkeypatch, frames: int) -> None:
    """Ctrl-C (the runner's request_stop) once ``frames`` frames are sent — in the first run only."""
    real_drain = armctl.host.runner.JobRunner._drain
    asked = []

    def drain(self):
        if self.view.frames_sent >= frames and not asked:
            asked.append(True)
            self.request_stop()
        real_drain(self)

    monkeypatch.setattr(armctl.host.runner.JobRunner, "_drain", drain)


def _targets_done(arm) -> list[tuple]:
    return [(round(e.command.x_mm, 1), round(e.command.y_mm, 1)) if isinstance(e.command, LinearMove)
            else (round(e.command.j1_deg, 1), round(e.command.j2_deg, 1)) for e in arm.execution_log
            if isinstance(e.command, (LinearMove, JointMove)) and e.outcome == DONE]


def _joint_job() -> str:
    """Joint moves (G6) of about 0.5 s, each to joints of their own: evidence is the joints."""
    lines = ["G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 S1000 F30 H3"]
    lines += [f"G6 J1={3 * (k + 1)} J2={(k % 5) * 2} F30" for k in range(30)]
    return "\n".join(lines) + "\n"


def _joint_targets() -> list[tuple]:
    return [(0.0, 0.0)] + [(3.0 * (k + 1), float((k % 5) * 2)) for k in range(30)]


def _job_targets() -> list[tuple]:
    targets = [(200.0, 0.0)] + [(200.0 + 5 * (k + 1), float((k % 5) * 4)) for k in range(30)]
    return targets


ARMS = [("", ""), ("fifo_frames = 50\nstatus_xyz_frame = \"robot\"\nspeed_factor = 0.7\n",
                   "&fifo_frames=50&status_xyz_frame=robot&speed_factor=0.7"),
        ("fifo_frames = 250\nspeed_factor = 2.0\n", "&fifo_frames=250&speed_factor=2.0")]


@pytest.mark.parametrize("arm_toml, arm_url", ARMS, ids=["document", "fifo50-robot-0.7", "fifo250-2.0"])
@pytest.mark.parametrize("control", ["queued", "arrival"])
@pytest.mark.parametrize("abort", ["pause", "reset-connector"])
def test_an_abort_and_its_printed_resume_run_every_line_exactly_once(one_arm, tmp_path, monkeypatch, control, abort,
                                                                     arm_toml, arm_url):
    (tmp_path / "armctl.toml").write_text(f'[connector]\ncontrol_frames = "{control}"\n{arm_toml}', encoding="utf-8")
    url = f"sim://?clock=virtual&control_frames={control}{arm_url}"
    _stop_after(monkeypatch, STOP_AFTER_FRAMES)
    first = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--port", url, "--abort", abort])
    assert first.exit_code == 130, first.output
    arm = one_arm[url].model
    if control == "arrival":  # the abort acted at once: the arm stopped with frames still queued
        aborts = [f.command for f in arm.frames_received if isinstance(f.command, (PauseToggle, ResetConnector))]
        assert aborts == ([PauseToggle(), ResetConnector()] if abort == "pause" else [ResetConnector()])
        assert arm.fifo_occupancy == 0  # nothing left queued for a later resume to start
    resume = re.search(r"^resume with: (.*)$", first.stdout, re.M)
    assert resume, first.output
    words = shlex.split(resume.group(1))
    assert words[:2] == ["armctl", "run"] and words[words.index("--port") + 1] == url
    assert ("--abort" in words) == (abort != "pause")  # every option that shaped the run

    second = CliRunner().invoke(main, words[1:] + ["--no-live"])
    assert second.exit_code == 0, second.output
    assert second.stdout.splitlines()[-1] == "finished: the arm finished the job"
    assert arm.frames_dropped == 0
    done = _targets_done(arm)
    collapsed = [t for k, t in enumerate(done) if k == 0 or done[k - 1] != t]  # an idempotent re-send
    assert collapsed == _job_targets(), (first.output, second.output)
    repeats = len(done) - len(collapsed)
    assert repeats <= 1  # at most the one frame in progress at the abort is re-sent


def test_the_arm_left_paused_with_a_queue_on_arrival_is_cleared_before_the_toggle(one_arm, tmp_path, monkeypatch):
    """Today's failure (issue 9): an arrival arm paused with line 9 still queued; ``--from-line 8``
    sent the toggle (the arm ran its queued 9), then 8 and 9 again.  Now the start of the run
    clears the queue first (RESET CONNECTOR acts as it lands), then resumes."""
    from armctl.core.protocol import LinearMove as Move

    (tmp_path / "armctl.toml").write_text('[connector]\ncontrol_frames = "arrival"\n', encoding="utf-8")
    url = "sim://?clock=virtual&control_frames=arrival"
    port = armctl.host.link.open_port(url)
    arm, clock = port.model, port.virtual_clock
    moves = [Move(200.0, 0.0, 250.0, 180.0, 0.0, 0.0, 1500.0, 3000.0),
             Move(230.0, 0.0, 250.0, 180.0, 0.0, 0.0, 1500.0, 600.0),
             Move(260.0, 0.0, 250.0, 180.0, 0.0, 0.0, 1500.0, 600.0)]
    for move in moves:
        port.write(move.encode())
    clock.advance_to(clock.now_s + 9.0)  # the first two run; the third is under way
    port.read(1 << 16)
    port.write(PauseToggle().encode())
    port.write(Move(290.0, 0.0, 250.0, 180.0, 0.0, 0.0, 1500.0, 600.0).encode())  # queued behind the frozen move
    clock.advance_to(clock.now_s + 1.0)
    port.read(1 << 16)
    assert arm.paused and arm.fifo_occupancy == 1
    result = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--port", url, "--from-line", "2"])
    assert result.exit_code == 0, result.output
    assert "reset host connector" in result.output
    assert (290.0, 0.0) not in _targets_done(arm)  # the queued frame never ran


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(stop_after=st.integers(2, 29), control=st.sampled_from(["queued", "arrival"]),
       abort=st.sampled_from(["pause", "reset-connector"]), factor=st.sampled_from([0.7, 1.0, 1.3, 2.0]),
       joints=st.booleans())
def test_wherever_the_abort_comes_the_resume_runs_every_line_once(tmp_path_factory, stop_after, control, abort, factor,
                                                                  joints):
    """Any moment of the job (a pause that lands mid-move, at a boundary between two moves, while
    the lead is being filled), either control mode, either abort, an arm slower or faster."""
    directory = tmp_path_factory.mktemp("arm")
    (directory / "job.txt").write_text(_joint_job() if joints else _job(), encoding="utf-8")
    (directory / "armctl.toml").write_text(f'[connector]\ncontrol_frames = "{control}"\nspeed_factor = {factor}\n')
    url = f"sim://?clock=virtual&control_frames={control}&speed_factor={factor}"
    with pytest.MonkeyPatch.context() as monkeypatch:
        monkeypatch.chdir(directory)
        monkeypatch.delenv("ARMCTL_PORT", raising=False)
        ports = _open_one_arm(monkeypatch)
        _stop_after(monkeypatch, stop_after)
        first = CliRunner().invoke(main, ["run", "job.txt", "--no-live", "--port", url, "--abort", abort])
        assert first.exit_code == 130, first.output
        words = shlex.split(re.search(r"^resume with: (.*)$", first.stdout, re.M).group(1))
        second = CliRunner().invoke(main, words[1:] + ["--no-live"])
    assert second.exit_code == 0, second.output
    arm = ports[url].model
    assert arm.frames_dropped == 0
    done = _targets_done(arm)
    collapsed = [t for k, t in enumerate(done) if k == 0 or done[k - 1] != t]
    assert collapsed == (_joint_targets() if joints else _job_targets()), (first.output, second.output)
    assert len(done) - len(collapsed) <= 1
