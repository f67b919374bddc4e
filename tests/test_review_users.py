"""The newcomer's path, as a user meets it: the names docs/api.md documents, and Ctrl-C in
``armctl move``/``home``.

Found in the review of main (wt-users): ``from armctl import ResumeRefused`` failed although
docs/api.md's table of errors names it beside ``ScriptError`` and ``JobFailed``, which import;
and ``armctl move`` on the wall clock, given Ctrl-C during a long move, printed nothing until the
arm was at rest (a minute here) and ignored a second Ctrl-C, where ``run`` says it is stopping at
once and a second press cuts the wait short (README: Stopping a job; docs/api.md: ``stop()``).
"""

from __future__ import annotations

import json
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ARMCTL = [sys.executable, "-m", "armctl"]
ENV = {key: value for key, value in os.environ.items() if key != "ARMCTL_PORT"}


def _documented_errors() -> list[str]:
    """The names in the first column of docs/api.md's table of errors (``| `Name` | when |``)."""
    text = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    table = text[text.index("| error | when |"):]
    names = []
    for row in table.splitlines()[2:]:
        if not row.startswith("|"):
            break
        names += re.findall(r"`(?:armctl\.)?(\w+)`", row.split("|")[1])
    return names


def test_every_documented_error_imports_from_armctl_in_a_fresh_process():
    names = _documented_errors()
    assert "ResumeRefused" in names and "ScriptError" in names, names
    program = ("import armctl\n"
               f"for name in {names!r}:\n"
               "    error = getattr(armctl, name)\n"
               "    assert issubclass(error, armctl.ArmctlError), name\n"
               "    assert name in armctl.__all__, name\n"
               f"from armctl import {', '.join(names)}\n"
               "print('ok')\n")
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=30, cwd=ROOT)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr


def test_resume_refused_from_armctl_is_the_one_the_api_raises(tmp_path):
    import armctl
    from armctl.errors import ResumeRefused

    assert armctl.ResumeRefused is ResumeRefused
    job = tmp_path / "job.txt"
    job.write_text("G4 P100\n", encoding="utf-8")
    with armctl.Arm.open(port="sim://?clock=virtual") as arm, pytest.raises(armctl.ResumeRefused):
        arm.run(job, resume=job)  # the script itself is no journal: refused, nothing sent


def _lines(stream, into: queue.Queue) -> None:
    for line in stream:
        into.put(line)
    into.put(None)


def _wait_for(lines: queue.Queue, seen: list[str], pattern: str, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            line = lines.get(timeout=max(0.01, deadline - time.monotonic()))
        except queue.Empty:
            break
        if line is None:
            break
        seen.append(line)
        if re.search(pattern, line):
            return True
    return False


@pytest.mark.realtime
@pytest.mark.timeout(60)
def test_move_says_at_once_that_ctrl_c_stops_it_and_a_second_press_ends_the_wait():
    # from the fixed pose 0, 313 mm at 300 mm/min: a minute of motion; Ctrl-C queues the pause
    # behind it (H5), so without a second press the command would wait for all of it
    process = subprocess.Popen([*ARMCTL, "move", "x=300", "y=-150", "z=40", "f=300", "--port", "sim://"], cwd=ROOT,
                               env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    errors: queue.Queue = queue.Queue()
    threading.Thread(target=_lines, args=(process.stderr, errors), daemon=True).start()
    seen: list[str] = []
    try:
        assert _wait_for(errors, seen, r"using the built-in simulator", 20), seen
        time.sleep(1.5)  # the move is written and running
        process.send_signal(signal.SIGINT)
        assert _wait_for(errors, seen, r"interrupted", 5), f"nothing said within 5 s of Ctrl-C: {seen}"
        time.sleep(0.5)
        process.send_signal(signal.SIGINT)
        code = process.wait(timeout=10)
        out = process.stdout.read()
    finally:
        process.kill()
    _wait_for(errors, seen, r"$^", 1)  # the rest of stderr
    assert code == 130, (code, seen)
    assert out.startswith("interrupted"), out
    assert not any("Traceback" in line for line in seen), seen


def test_e010_names_only_commands_that_take_from_line():
    # README's and docs/lint.md's E010 rows said "--from-line of compile/run"; compile has no --from-line
    from armctl.ui.cli import main

    for document in (ROOT / "README.md", ROOT / "docs" / "lint.md"):
        row = next(line for line in document.read_text(encoding="utf-8").splitlines() if line.startswith("| E010 |"))
        named = re.findall(r"`(\w+)`", row.split("`--from-line` of ", 1)[1].split(" must", 1)[0])
        assert named, row
        for name in named:
            options = {option for param in main.commands[name].params for option in param.opts}
            assert "--from-line" in options, (document.name, name)


@pytest.mark.realtime
@pytest.mark.timeout(60)
def test_sim_tcp_serves_one_program_after_another_the_same_arm():
    # README (Platforms): "On Windows serve the simulator with `armctl sim --tcp 5555` and use
    # `--port socket://127.0.0.1:5555`" — it ended, exit 0, when the first program closed its socket,
    # so the second command was refused; `sim --pty` keeps serving the same arm (keep_serving)
    import socket

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    sim = subprocess.Popen([*ARMCTL, "sim", "--tcp", str(port)], cwd=ROOT, env=ENV,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    url = f"socket://127.0.0.1:{port}"
    try:
        assert "(Ctrl-C to stop)" in sim.stdout.readline()
        def armctl(*arguments):
            return subprocess.run([*ARMCTL, *arguments, "--port", url], cwd=ROOT, env=ENV, capture_output=True,
                                  text=True, timeout=30)

        first = armctl("status", "--once", "--json")
        assert first.returncode == 0, first.stderr
        moved = armctl("move", "z=250", "--json")  # exit 1: "finished, unproven" on a socket (FIFO not probed)
        assert moved.stdout, moved.stderr  # before: "connection refused", the simulator gone
        assert json.loads(moved.stdout)["outcome"].startswith("finished"), (moved.stdout, moved.stderr)
        third = armctl("status", "--once", "--json")
        assert third.returncode == 0, third.stderr
        assert abs(json.loads(third.stdout)["z"] - 250) < 0.5, third.stdout  # the same arm, moved
        assert sim.poll() is None
        sim.send_signal(signal.SIGINT)
        assert sim.wait(timeout=10) == 130
    finally:
        sim.kill()


def test_run_result_outcome_is_the_plain_text_docs_api_prints(tmp_path):
    # docs/api.md, "Several arms": print(results)  # {'left': 'finished', 'right': 'finished'} —
    # it printed {'left': <Outcome.FINISHED: 'finished'>, …}: the job engine's enum leaked into the result
    import armctl

    job = tmp_path / "job.txt"
    job.write_text("G1 X210 Y0 Z290 A180 B0 C0 S1500 F6000\nG1 Z280\n", encoding="utf-8")
    with armctl.Arm.open(port="sim://?clock=virtual") as arm:
        results = {"left": arm.run(job).outcome, "moved": arm.move(z=250).outcome}

        def stop_at_once(progress):
            arm.stop()

        results["stopped"] = arm.run(job, on_progress=stop_at_once).outcome
    assert repr(results) == "{'left': 'finished', 'moved': 'finished', 'stopped': 'interrupted'}"
    assert all(type(outcome) is str for outcome in results.values())


def test_estimate_takes_the_line_rate_of_armctl_toml_as_run_does(tmp_path):
    # `baud = 115200` in armctl.toml: `armctl config` and `run --dry-run` said 115200, `estimate`
    # planned at 9600 — 10.1 s for a job of 200 tiny moves that runs in 1.1 s
    lines = ["G1 X210 Y0 Z290 A180 B0 C0 S1500 F6000"] + [f"G1 Z{290 - (i % 2) * 0.5}" for i in range(200)]
    (tmp_path / "tiny.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")
    (tmp_path / "armctl.toml").write_text("baud = 115200\n", encoding="utf-8")

    def job_s(*arguments):
        done = subprocess.run([*ARMCTL, *arguments], cwd=tmp_path, env=ENV, capture_output=True, text=True, timeout=60)
        assert done.returncode == 0, done.stderr
        return float(re.search(r"job time\s+([\d.]+) s", done.stdout).group(1))

    configured = job_s("estimate", "tiny.txt")
    assert configured == job_s("estimate", "tiny.txt", "--baud", "115200") == job_s("run", "tiny.txt", "--dry-run")
    assert configured < job_s("estimate", "tiny.txt", "--baud", "9600") / 2  # the option still wins


def test_serve_without_its_extra_names_a_pip_command_that_installs_it():
    # README (Install): "`armctl-serial` is not on the index; install it from a checkout" — the
    # message said pip install 'armctl-serial[serve]', which the index cannot satisfy
    code = "import sys; sys.modules['aiohttp'] = None; from armctl.ui.cli import main; main(['serve'])"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=30, cwd=ROOT)
    assert done.returncode == 2, done.stderr
    assert "pip install -e '.[serve]'" in done.stderr and "checkout" in done.stderr, done.stderr
    assert "armctl-serial[" not in done.stderr, done.stderr
