"""Review of the Python API as a programmer meets it: a callback that calls back into the arm,
a callback or observer that fails while the job stops, ``sys.exit`` in a callback, a ``log=``
that cannot be written, a program that ends with moves queued.

Each fault, as found: the arm left running its queued frames with no abort sequence sent, a
job run inside another job's stream, a move queued with ``wait=False`` dropped at exit without
a word.  In virtual time (``sim://?clock=virtual``), and a fresh process where the exit matters.
"""
from __future__ import annotations

import subprocess
import sys
import textwrap
import threading

import pytest

from armctl import Arm, ArmctlError, JobFailed, JobObserver
from armctl.core.protocol import PauseToggle

pytestmark = pytest.mark.timeout(30)

VIRTUAL = "sim://?clock=virtual"
# 61 frames, about 20 s of arm time: still moving when a stop comes at frame 5
LONG_JOB = "G90\nG1 X250 Y-50 Z150 A180 B0 C0 F3000 S1000\nO<a> repeat [30]\nG1 Z100 F3000\nG1 Z150\nO<a> endrepeat\n"


def received(arm: Arm) -> list:
    return [frame.command for frame in arm._link.port.model.frames_received]


def toggles(arm: Arm) -> int:
    return sum(isinstance(command, PauseToggle) for command in received(arm))


def stop_at_frame(arm: Arm, frames: int):
    def on_progress(progress) -> None:
        if progress.frames_sent == frames:
            arm.stop()
    return on_progress


def resume_asker(arm: Arm, answers: list):
    """A function that asks ``arm.resume()`` and keeps its answer, or the error's text, in ``answers``."""
    def ask() -> None:
        try:
            answers.append(arm.resume())
        except ArmctlError as error:
            answers.append(str(error))
    return ask


def assert_stopped_at_rest(arm: Arm) -> None:
    """The abort went (one pause toggle) and the arm stays where it stopped for 10 s of its clock."""
    assert toggles(arm) == 1, received(arm)
    before = arm.status().position_mm
    arm._call(lambda: arm._link.wait_until(lambda state: False, 10.0))
    assert arm.status().paused and arm.status().position_mm == before


def test_an_observer_note_that_raises_while_the_job_stops_does_not_skip_the_abort():
    class Raises(JobObserver):
        def note(self, text):
            raise RuntimeError("note failed")

    with Arm.open(VIRTUAL) as arm:
        result = arm.run(LONG_JOB, on_progress=stop_at_frame(arm, 5), observer=Raises())
        assert result.outcome == "interrupted"
        assert any("note failed" in message for message in result.messages), result.messages
        assert_stopped_at_rest(arm)


def test_an_observer_update_that_raises_during_the_abort_does_not_cut_it_short():
    stopping = []

    class Raises(JobObserver):
        def update(self, view):
            if stopping:
                raise RuntimeError("update failed")

    with Arm.open(VIRTUAL) as arm:
        def on_progress(progress):
            if progress.frames_sent == 5:
                stopping.append(True)
                arm.stop()

        result = arm.run(LONG_JOB, on_progress=on_progress, observer=Raises())
        assert result.outcome == "interrupted"
        assert_stopped_at_rest(arm)


def test_sys_exit_in_on_progress_stops_the_arm_before_it_leaves():
    with Arm.open(VIRTUAL) as arm:
        def on_progress(progress):
            if progress.frames_sent == 5:
                sys.exit(3)

        with pytest.raises(SystemExit):
            arm.run(LONG_JOB, on_progress=on_progress)
        assert_stopped_at_rest(arm)


@pytest.mark.parametrize("call", ["run", "move", "home", "wait", "close"])
def test_a_call_that_waits_for_the_arm_from_inside_its_own_job_is_refused(call):
    asked = []
    with Arm.open(VIRTUAL) as arm:
        calls = {"run": lambda: arm.run("G4 P100\n"), "move": lambda: arm.move(x=200),
                 "home": lambda: arm.home(), "wait": arm.wait, "close": arm.close}

        def on_progress(progress):
            if progress.frames_sent == 2 and not asked:
                try:
                    calls[call]()
                    asked.append("ran")
                except ArmctlError as error:
                    asked.append(str(error))
                    raise

        with pytest.raises(JobFailed) as failed:
            arm.run(LONG_JOB, on_progress=on_progress)
        assert "on_progress" in asked[0] and "wait=False" in asked[0], asked
        assert failed.value.__cause__ is not None
        assert len(received(arm)) == failed.value.result.frames_sent + 1  # the job's frames and its abort's toggle
        assert arm.run("G4 P100\n").finished  # the arm is usable after


@pytest.mark.parametrize("how", ["closed", "read-only"])
def test_a_log_that_cannot_be_written_is_refused_at_the_call(tmp_path, how):
    path = tmp_path / "job.log"
    path.write_text("")
    log = open(path, "r" if how == "read-only" else "w", encoding="utf-8")
    if how == "closed":
        log.close()
    with Arm.open(VIRTUAL) as arm:
        with pytest.raises((TypeError, ValueError), match="log"):
            arm.run("G4 P100\n", log=log)
        assert received(arm) == []
    log.close()


def test_a_program_that_ends_with_queued_moves_runs_them_before_it_exits(tmp_path):
    program = textwrap.dedent("""
        import atexit
        from armctl import Arm
        models = []  # registered before the arm opens: runs after armctl's own exit handlers (last in, first out)
        atexit.register(lambda: print("received", len(models[0].frames_received), flush=True))
        arm = Arm.open("sim://?clock=virtual")
        models.append(arm._link.port.model)
        arm.move(x=250, y=0, z=150, a=180, b=0, c=0, f=3000, wait=False)
        arm.move(x=200, f=300, wait=False)
    """)
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=25, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["received", "2"], done.stdout + done.stderr


def run_program(program: str, tmp_path, timeout_s: float = 25) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(program)], capture_output=True, text=True,
                          timeout=timeout_s, cwd=tmp_path)


def test_a_program_that_dies_of_an_exception_with_queued_moves_stops_the_arm(tmp_path):
    done = run_program("""
        import atexit, time
        from armctl.core.protocol import PauseToggle
        from armctl import Arm
        models = []  # runs after armctl's own exit handlers (last in, first out)
        atexit.register(lambda: print("frames", len(models[0].frames_received),
                                      "toggles", sum(isinstance(f.command, PauseToggle) for f in models[0].frames_received)))
        arm = Arm.open("sim://?speed=4")
        models.append(arm._link.port.model)
        arm.move(x=250, y=0, z=150, a=180, b=0, c=0, f=3000, wait=False)
        arm.move(x=150, f=300, wait=False)  # 20 s of the arm's time: 5 s on this 4x simulator
        arm.move(x=250, f=300, wait=False)
        time.sleep(1.5)
        raise RuntimeError("the program failed")
    """, tmp_path)
    assert done.returncode == 1 and "RuntimeError: the program failed" in done.stderr, done.stderr
    assert done.stdout.split() == ["frames", "3", "toggles", "1"], done.stdout + done.stderr  # 2 moves and the abort


def test_a_queued_move_that_fails_at_exit_is_said_on_stderr(tmp_path):
    done = run_program("""
        from armctl import Arm
        arm = Arm.open("sim://?clock=virtual&loss=1", status_timeout_s=0.2)  # every status frame lost
        arm.move(x=250, y=0, z=150, a=180, b=0, c=0, f=3000, wait=False)
    """, tmp_path)
    assert done.returncode == 0, done.stderr
    assert "wait=False failed: no complete status" in done.stderr, done.stderr


def test_ctrl_c_while_the_with_block_waits_for_queued_moves_stops_the_arm(tmp_path):
    done = run_program("""
        import os, signal, threading, time
        from armctl import Arm
        start = time.monotonic()
        try:
            with Arm.open("sim://?speed=4") as arm:
                model = arm._link.port.model
                arm.move(x=250, y=0, z=150, a=180, b=0, c=0, f=3000, wait=False)
                arm.move(x=150, f=300, wait=False)  # 20 s of the arm's time: 5 s on this 4x simulator
                arm.move(x=250, f=300, wait=False)
                threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        except KeyboardInterrupt:
            print("stopped", len(model.frames_received), round(time.monotonic() - start, 1))
    """, tmp_path, timeout_s=40)
    words = done.stdout.split()
    assert words[:2] == ["stopped", "2"], done.stdout + done.stderr  # the third move is never sent
    assert float(words[2]) < 8, done.stdout


def test_stop_from_a_signal_handler_that_comes_while_a_call_holds_the_lock_does_not_deadlock(tmp_path):
    program = """
        import os, signal
        from armctl import Arm
        arm = Arm.open("sim://?clock=virtual")
        signal.signal(signal.SIGTERM, lambda number, frame: arm.stop("stopped by SIGTERM"))
        with arm._tasks.lock:  # the moment the signal comes: arm.move(wait=False) queueing, say
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(1000):  # (the handler runs in this thread, between two bytecodes)
                pass
        arm.move(x=250, y=0, z=150, a=180, b=0, c=0, f=3000)
        arm.close()
        print("handled")
    """
    try:
        done = run_program(program, tmp_path, timeout_s=10)
    except subprocess.TimeoutExpired:
        pytest.fail("deadlocked: the program did not end within 10 s")
    assert done.stdout.split() == ["handled"], done.stdout + done.stderr


@pytest.mark.parametrize("call", ["feed_override", "toggle_pause"])
def test_a_control_call_after_close_says_the_arm_is_closed(call):
    arm = Arm.open(VIRTUAL)
    arm.close()
    with pytest.raises(ArmctlError, match="is closed"):
        arm.feed_override(50) if call == "feed_override" else arm.toggle_pause()


@pytest.mark.parametrize("where", ["observer", "another thread"])
def test_resume_while_the_job_stops_is_refused_and_the_arm_stays_paused(where):
    answers = []
    with Arm.open(VIRTUAL + "&control_frames=arrival") as arm:
        ask = resume_asker(arm, answers)

        class Resumes(JobObserver):
            def update(self, view):  # the job stops, and the arm reports the abort's pause
                if answers or "stop" not in stage or not arm._link.snapshot()[0].paused:
                    return
                if where == "observer":
                    ask()
                else:
                    asking = threading.Thread(target=ask)
                    asking.start()
                    asking.join(2.0)  # (a resume that waits for the job's end would wait for this call)
                    answers.append(answers.pop() if answers else "waited for the job's end")

            def note(self, text):
                stage.append("stop")

        stage: list = []

        result = arm.run(LONG_JOB, on_progress=stop_at_frame(arm, 5), observer=Resumes())
        assert result.outcome == "interrupted"
        assert answers and "stopping" in str(answers[0]), answers
        assert_stopped_at_rest(arm)


def test_status_json_at_once_after_close_says_the_arm_is_closed():
    arm = Arm.open("sim://")
    arm.close()
    with pytest.raises(ArmctlError, match="is closed"):
        arm.status_json(at_once=True)


def test_ctrl_c_caught_around_wait_stops_the_queued_moves(tmp_path):
    done = run_program("""
        import os, signal, threading, time
        from armctl import Arm
        with Arm.open("sim://?speed=4") as arm:
            model = arm._link.port.model
            arm.move(x=250, y=0, z=150, a=180, b=0, c=0, f=3000, wait=False)
            arm.move(x=150, f=300, wait=False)  # 20 s of the arm's time: 5 s on this 4x simulator
            arm.move(x=250, f=300, wait=False)
            threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
            try:
                arm.wait()
            except KeyboardInterrupt:
                paused = arm.status().paused  # (after the stopped move's end)
                toggles = sum(type(frame.command).__name__ == "PauseToggle" for frame in model.frames_received)
                print("stopped", len(model.frames_received) - toggles, toggles, paused)
    """, tmp_path, timeout_s=40)
    words = done.stdout.split()
    assert words[0] == "stopped" and int(words[1]) < 3 and words[2:] == ["1", "True"], done.stdout + done.stderr


@pytest.mark.parametrize("where", ["api /dev/null", "api pipe", "cli /dev/null"])
def test_a_log_written_through_a_device_or_a_pipe_does_not_fail_the_job(tmp_path, where):
    script = tmp_path / "job.txt"
    script.write_text("G4 P100\nG4 P100\n")
    if where == "cli /dev/null":
        done = subprocess.run([sys.executable, "-m", "armctl", "run", str(script), "--port", "sim://?speed=20",
                               "--log", "/dev/null"], capture_output=True, text=True, timeout=25)
        assert done.returncode == 0, done.stderr
        return
    import os
    if where == "api pipe":
        reading, writing = os.pipe()
        log = os.fdopen(writing, "w", encoding="utf-8")
        threading.Thread(target=lambda: [None for _ in os.fdopen(reading, encoding="utf-8")], daemon=True).start()
    else:
        log = open(os.devnull, "w", encoding="utf-8")
    with log, Arm.open("sim://?speed=20") as arm:  # (a wall clock: each frame's record is made durable)
        assert arm.run(script, log=log).finished


def test_a_resume_asked_just_before_a_stop_is_not_carried_out_on_the_idle_arm():
    answers: list = []
    with Arm.open(VIRTUAL + "&control_frames=arrival") as arm:
        steps: list = []

        ask = resume_asker(arm, answers)

        def on_progress(progress):
            if progress.frames_sent == 5 and not steps:
                steps.append("pause")
                arm.pause()
            elif steps == ["pause"] and progress.paused:
                steps.append("resume, stop")
                asking = threading.Thread(target=ask)
                asking.start()
                while not arm._tasks.job._asked:  # the resume is handed to the engine, not yet carried out
                    asking.join(0.001)
                arm.stop()

        result = arm.run(LONG_JOB, on_progress=on_progress)
        assert result.outcome == "interrupted"
        arm.wait()
        for _ in range(100):
            if answers:
                break
            threading.Event().wait(0.02)
        assert answers and "stopped" in str(answers[0]), answers
        assert toggles(arm) == 1 and arm.status().paused
