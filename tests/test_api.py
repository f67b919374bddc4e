"""The Python API (``from armctl import Arm``) as a user's program sees it.

Against the simulator on a virtual clock in-process (model time moves only while the arm's
worker waits, so every figure is the same on any machine), the same in a fresh process, against
``armctl sim --pty`` started as another process in real time (a job of under a second), two
arms driven at once from two threads, and every way a call can fail: a script with errors
(nothing written: the simulated arm's own record of frames received is empty), a timeout, a
job paused, resumed and stopped while it runs.
"""

from __future__ import annotations

import os
import signal
import struct
import subprocess
import sys
import threading
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armctl
from armctl import Arm, ArmTimeout, JobFailed, RunResult, ScriptError
from armctl.core.protocol import JointMove, LinearMove, PauseToggle
from armctl.host.api import move_line
from armctl.script import InitialState, ScriptSnapshot, compile_text

SCRIPTS = Path(__file__).resolve().parent / "data" / "scripts_cli"
SHORT = SCRIPTS / "short_job.txt"  # 5 frames, under a second of arm time
TIMED = SCRIPTS / "timed_job.txt"  # a pick and place, about 30 s of arm time
VIRTUAL = "sim://?clock=virtual"

EXAMPLE = """
from armctl import Arm
progress = []
with Arm.open(port=PORT) as arm:
    first = arm.move(x=250, y=0, z=150, f=3000)
    assert first.finished and first.frames_sent == 1, first
    assert arm.move(j1=10, f=20, wait=False) is None
    result = arm.run(JOB, on_progress=progress.append)
    status = arm.status()
    pause_sent = arm.pause(); resume_sent = arm.resume(); arm.stop()
"""


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)


def model_of(arm: Arm):
    """The simulated arm behind a sim:// port (its own record of what it received)."""
    return arm._link.port.model


def commands_received(arm: Arm) -> list:
    return [frame.command for frame in model_of(arm).frames_received]


def compiled(path: Path) -> list:
    return [statement.command for statement in ScriptSnapshot(str(path), path.read_bytes()).compile()]


def test_the_issue_example_against_the_simulator_in_process(capfd):
    names = {"PORT": VIRTUAL, "JOB": str(SHORT)}
    exec(EXAMPLE, names)
    result, status, progress = names["result"], names["status"], names["progress"]
    assert isinstance(result, RunResult)
    assert (result.outcome, result.frames_sent, result.total_frames) == ("finished", 5, 5)
    assert (result.last_line_sent, result.last_line_executed, result.resume_line) == (6, 6, None)
    assert result.arm_time_s is not None and result.arm_time_s > 0
    assert progress and progress[-1].frames_sent == 5 and progress[-1].total_frames == 5
    # the job ends at X220 Y10 Z280 (short_job.txt): the status is the arm's report after it
    assert status.position_mm == pytest.approx((220.0, 10.0, 280.0), abs=0.2)
    assert status.pwm_us == 1000 and status.paused is False
    assert set(status.ages_s) >= {"position", "joints", "pause_pwm"}
    assert all(age is not None and age >= 0 for age in status.ages_s.values())
    assert (names["pause_sent"], names["resume_sent"]) == (True, True)  # stop() on an idle arm: nothing
    assert capfd.readouterr() == ("", "")  # nothing printed, not even the simulator banner


def test_the_issue_example_in_a_fresh_process_with_the_port_from_the_environment(tmp_path):
    program = EXAMPLE.replace("Arm.open(port=PORT)", "Arm.open()") + "print(result.outcome, result.frames_sent, status.paused)\n"
    env = {**os.environ, "ARMCTL_PORT": VIRTUAL, "JOB": str(SHORT)}
    done = subprocess.run([sys.executable, "-c", "import os; JOB = os.environ['JOB']\n" + program],
                          capture_output=True, text=True, timeout=60, env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "finished 5 False\n"
    assert done.stderr == ""


def test_importing_armctl_does_not_import_the_api_and_every_exported_name_resolves():
    code = ("import sys, armctl; print('armctl.host.api' in sys.modules, 'armctl.host.jobflow' in sys.modules);"
            "[getattr(armctl, name) for name in armctl.__all__]; print('armctl.host.api' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=30)
    assert done.stdout == "False False\nTrue\n", done.stderr
    assert issubclass(ScriptError, armctl.ArmctlError) and issubclass(ArmTimeout, JobFailed)
    with pytest.raises(AttributeError):
        armctl.NoSuchName  # noqa: B018


def test_a_script_with_errors_raises_with_its_diagnostics_and_nothing_is_written(tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_text("G1 X210 Y0 Z290 A180 B0 C0 S1500 F6000\nG1 X5 x6\nG7\n")
    with Arm.open(port=VIRTUAL) as arm:
        with pytest.raises(ScriptError) as raised:
            arm.run(bad)
        assert [d.code for d in raised.value.diagnostics] == ["E003", "E002"]
        assert raised.value.errors == 2
        with pytest.raises(ScriptError) as raised:
            arm.move(x=210, f=-5, wait=False)  # refused at once, even when not waited for
        assert raised.value.diagnostics[0].code == "E005"
        with pytest.raises(ScriptError):
            arm.run("G1 X1\n", from_line=1)  # text: needs A, B, C, S
        assert commands_received(arm) == []


def test_a_path_and_text_are_told_apart_and_an_unreadable_path_says_what_to_do(tmp_path):
    with Arm.open(port=VIRTUAL) as arm:
        text = arm.run(SHORT.read_text())  # a str with a line break: the script itself
        path = arm.run(str(SHORT))  # a str without one: a file
        assert text.frames_sent == path.frames_sent == 5
        with pytest.raises(JobFailed, match=r"cannot read G4 P10: .*end a one-line script with \\n"):
            arm.run("G4 P10")
        assert arm.run("G4 P10\n").frames_sent == 1


def test_move_builds_one_line_through_the_compiler():
    assert move_line(x=250, y=0, z=150.5, f=3000) == "G1 X250 Y0 Z150.5 F3000\n"
    assert move_line(j2=-30, j1=1e-7, f=20) == "G6 J1=0.0000001 J2=-30 F20\n"
    assert move_line(z=Fraction(1, 4), s=1500) == "G1 Z0.25 S1500\n"  # any real number
    with pytest.raises(ValueError, match="not a finite number"):
        move_line(x=float("nan"))
    with pytest.raises(TypeError, match="must be a number"):
        move_line(x="5")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="at least one word"):
        move_line()


def test_queued_moves_stream_after_move_returns_and_run_exactly_once_before_the_next_call():
    with Arm.open(port=VIRTUAL) as arm:
        for x in (200, 210, 220):
            assert arm.move(x=x, y=0, z=250, f=6000, wait=False) is None
        last = arm.move(j1=5, f=30)  # blocking: runs after the three queued moves
        assert last.finished
        received = commands_received(arm)
        assert [type(c) for c in received] == [LinearMove] * 3 + [JointMove]
        assert [c.x_mm for c in received[:3]] == [200, 210, 220]
        assert arm.status().joints_deg[0] == pytest.approx(5, abs=0.05)
        arm.move(x=230, y=0, z=250, f=6000, wait=False)
    # close() (the end of the with block) waited for the last queued move
    assert [c.x_mm for c in commands_received(arm) if isinstance(c, LinearMove)] == [200, 210, 220, 230]


def test_a_queued_move_that_fails_cancels_the_rest_and_its_error_comes_at_the_next_call():
    with Arm.open(port=VIRTUAL) as arm:
        arm.move(j1=5, f=30, wait=False, timeout=0.1)  # times out: stopped, its ArmTimeout kept
        arm.move(j1=6, f=30, wait=False)  # cancelled: the arm is not where it assumed
        with pytest.raises(ArmTimeout):
            arm.status()
        assert [type(c) for c in commands_received(arm)] == [JointMove, PauseToggle]
        assert arm.status().joints_deg[0] is not None  # the error was raised once; the arm goes on


def test_the_timeout_raises_stops_the_job_and_says_how_far_it_went():
    with Arm.open(port=VIRTUAL) as arm:
        with pytest.raises(ArmTimeout) as raised:
            arm.run(TIMED, timeout=2.0)
        result = raised.value.result
        assert result.outcome == "interrupted"
        assert 0 < result.frames_sent < result.total_frames
        assert result.resume_line is not None
        assert isinstance(commands_received(arm)[-1], PauseToggle)  # the abort sequence
        # the next job resumes the arm the stop left paused, and runs
        assert arm.run(SHORT).finished


def test_stop_from_another_thread_interrupts_the_running_job():
    reached, stopped = threading.Event(), threading.Event()

    def on_progress(progress):
        if progress.frames_sent >= 3 and not reached.is_set():
            reached.set()
            assert stopped.wait(10)

    with Arm.open(port=VIRTUAL) as arm:
        result_box = []
        job = threading.Thread(target=lambda: result_box.append(arm.run(TIMED, on_progress=on_progress)))
        job.start()
        assert reached.wait(30)
        arm.stop()  # from this thread while the worker is inside the job
        stopped.set()
        job.join(30)
        (result,) = result_box
        assert result.outcome == "interrupted"
        assert result.frames_sent < result.total_frames and result.resume_line is not None
        # continue where it stopped: every remaining frame goes, the job finishes
        rest = arm.run(TIMED, from_line=result.resume_line)
        assert rest.finished


@pytest.mark.parametrize("control", ["queued", "arrival"])
def test_pause_and_resume_a_running_job_it_finishes_every_frame_once(control):
    events = []

    def on_progress(progress):
        if progress.frames_sent >= 3 and not events:
            events.append(("pause", arm.pause(), progress.elapsed_s))
        elif len(events) == 1 and progress.elapsed_s - events[0][2] >= 3.0:
            events.append(("resume", arm.resume(), progress.elapsed_s))

    # the profile says how the arm takes control frames, as a probe would have found (else a job with
    # a POSE on an arrival arm ends "finished, unproven")
    from armctl.host.profile import default_profile, with_connector

    profile = with_connector(default_profile(), {"control_frames": control}, "the test's arm")
    with Arm.open(port=f"{VIRTUAL}&control={control}", profile=profile) as arm:
        result = arm.run(TIMED, on_progress=on_progress)
        assert [(name, sent) for name, sent, _ in events] == [("pause", True), ("resume", True)]
        assert result.finished
        received = commands_received(arm)
        toggles = [i for i, c in enumerate(received) if isinstance(c, PauseToggle)]
        assert len(toggles) == 2 and toggles[1] == toggles[0] + 1  # the feed was held while paused (H5)
        assert [c for c in received if not isinstance(c, PauseToggle)] == compiled(TIMED)  # every frame once


def test_pause_and_resume_from_another_thread_while_a_job_runs():
    """pause() and resume() from a thread that is not the arm's: each is a request the worker
    acts on between two writes, and the caller gets its answer."""
    answers, helpers = [], []

    def ask(method):
        helper = threading.Thread(target=lambda: answers.append((method.__name__, method())))
        helpers.append(helper)
        helper.start()
        # hold this callback (the worker) until the request is queued, so the next update sees it
        for _ in range(10_000):
            if not arm._job.runner.requests.empty() or not helper.is_alive():
                return
            threading.Event().wait(0.001)

    def on_progress(progress):
        if progress.frames_sent >= 3 and not helpers:
            ask(arm.pause)
        elif len(helpers) == 1 and progress.paused and not helpers[0].is_alive():
            ask(arm.resume)

    with Arm.open(port=VIRTUAL) as arm:
        result = arm.run(TIMED, on_progress=on_progress)
        for helper in helpers:
            helper.join(10)
        assert answers == [("pause", True), ("resume", True)]
        assert result.finished
        assert [c for c in commands_received(arm) if not isinstance(c, PauseToggle)] == compiled(TIMED)


def test_an_error_in_on_progress_stops_the_job_and_is_the_cause_of_job_failed():
    def on_progress(progress):
        if progress.frames_sent >= 2:
            raise ValueError("the caller's own bug")

    with Arm.open(port=VIRTUAL) as arm:
        with pytest.raises(JobFailed, match="the job ended failed: .*ValueError: the caller's own bug") as raised:
            arm.run(TIMED, on_progress=on_progress)
        assert isinstance(raised.value.__cause__, ValueError)
        result = raised.value.result
        assert result.outcome == "failed" and result.resume_line is not None
        assert isinstance(commands_received(arm)[-1], PauseToggle)  # the abort sequence went
        assert arm.run(SHORT).finished  # and the arm goes on


def test_pause_and_resume_an_idle_arm_follow_the_pause_rule():
    with Arm.open(port=VIRTUAL) as arm:
        assert arm.pause() is True
        assert arm.status().paused is True
        assert arm.pause() is False  # already paused: a toggle would resume it
        assert arm.resume() is True and arm.resume() is False
        assert commands_received(arm) == [PauseToggle(), PauseToggle()]


def test_two_arms_at_once_in_two_threads_each_sees_only_its_own_frames():
    jobs = {"a": SHORT, "b": TIMED}
    results, arms, errors = {}, {}, []

    def drive(name):
        try:
            with Arm.open(port=VIRTUAL) as arm:
                arms[name] = arm
                results[name] = arm.run(jobs[name])
                arm.move(x=215 if name == "a" else 225, y=0, z=280, f=6000)
        except BaseException as error:  # reported below, in the test's thread
            errors.append(error)

    threads = [threading.Thread(target=drive, args=(name,)) for name in jobs]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    assert errors == []
    assert results["a"].finished and results["b"].finished
    for name, path in jobs.items():
        received = commands_received(arms[name])
        assert received[:-1] == compiled(path)
        assert received[-1].x_mm == (215 if name == "a" else 225)


def test_the_api_installs_no_signal_handler():
    before = {number: signal.getsignal(number) for number in (signal.SIGINT, signal.SIGTERM)}
    with Arm.open(port=VIRTUAL) as arm:
        arm.run(SHORT)
    assert {number: signal.getsignal(number) for number in before} == before


@pytest.mark.realtime
def test_the_example_against_armctl_sim_pty_in_another_process(tmp_path, sim_pty):
    program = (
        "from armctl import Arm\n"
        "import sys\n"
        "with Arm.open(port=sys.argv[1]) as arm:\n"
        "    result = arm.run(sys.argv[2], timeout=10)\n"
        "    arm.move(z=275, f=6000, wait=False, timeout=10)\n"
        "    status = arm.status()\n"
        "    print(result.outcome, result.frames_sent, round(status.position_mm[2]), arm.pause(), arm.resume())\n"
        "    arm.stop()\n"
    )
    # the arm's FIFO size as `armctl probe --write` records it: a device path is proven only so
    # (without it the run ends "finished, unproven")
    (tmp_path / "armctl.toml").write_text("[connector]\nfifo_frames = 200\n")
    done = subprocess.run([sys.executable, "-c", program, sim_pty, str(SHORT)],
                          capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "finished 5 275 True True\n"
    assert done.stderr == ""


_FLOAT32_MAX = 3.4028234663852886e38
finite = st.floats(min_value=-_FLOAT32_MAX, max_value=_FLOAT32_MAX, allow_nan=False, allow_infinity=False)


@settings(max_examples=200, deadline=None)
@given(x=finite, j2=finite)
def test_move_words_reach_the_frame_as_the_compiler_reads_them(x, j2):
    """move() only writes text: the compiler reads it back to exactly the value given (as the
    float32 the frame carries), for any finite number — no exponent, no rounding of our own."""
    initial = InitialState(pose=(200.0, 0.0, 250.0, 180.0, 0.0, 0.0), joints_deg=(0.0,) * 6, pwm_us={1: 1500.0})
    (linear,) = [s.command for s in compile_text(move_line(x=x, f=3000), initial=initial)]
    (joint,) = [s.command for s in compile_text(move_line(j2=j2, f=20), initial=initial)]
    assert linear.x_mm == struct.unpack("<f", struct.pack("<f", x))[0]
    assert joint.j2_deg == struct.unpack("<f", struct.pack("<f", j2))[0]


def test_open_errors_are_the_commands_errors_and_print_nothing(capfd, tmp_path):
    with pytest.raises(armctl.ConfigError, match="clock must be .wall. or .virtual."):
        Arm.open(port="sim://?clock=sideways")
    with pytest.raises(armctl.PortError, match="no such device"):
        Arm.open(port=str(tmp_path / "ttyNOPE"))
    with pytest.raises(armctl.ConfigError, match="^port is empty"):  # the API's own word for it, not --port
        Arm.open(port=" ")
    assert capfd.readouterr() == ("", "")


@pytest.mark.parametrize("kwargs, name", [
    ({"lead_s": float("nan")}, "lead_s"), ({"lead_s": 0}, "lead_s"), ({"status_timeout_s": float("inf")}, "status_timeout_s"),
    ({"baud": float("nan")}, "baud"), ({"baud": 9600.5}, "baud"), ({"baud": True}, "baud"),
])
def test_open_refuses_numbers_outside_the_clis_ranges_before_the_port_opens(kwargs, name, monkeypatch):
    import armctl.host.link

    opened = []
    monkeypatch.setattr(armctl.host.link, "open_port", lambda *args, **kw: opened.append(args))
    with pytest.raises(ValueError, match=name):
        Arm.open(port=VIRTUAL, **kwargs)
    assert opened == []


@pytest.mark.parametrize("timeout", [float("nan"), float("inf"), -1, 0, "5"])
def test_a_timeout_that_could_never_fire_or_fires_at_once_is_refused(timeout):
    with Arm.open(port=VIRTUAL) as arm:
        with pytest.raises(ValueError, match="timeout"):
            arm.move(x=250, y=0, z=150, f=3000, timeout=timeout)
        with pytest.raises(ValueError, match="timeout"):
            arm.status(timeout=timeout)
        assert arm.move(x=250, y=0, z=150, f=3000, timeout=30).finished  # nothing was queued by the refusals
