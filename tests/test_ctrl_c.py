"""Ctrl-C: every long-running command exits 130 (README) with the terminal restored, and the
run panel stays one panel when a message is printed while it is live.

Issue 10: ``status --watch`` and ``sim --pty``/``--tcp`` exited 0 on Ctrl-C; ``run`` left a
stray partial copy of its panel above the final one (a raw stderr write under rich Live).

Exit codes go through a fresh process and a real SIGINT; the child gets the default SIGINT
handler back (the test runner may have been started with SIGINT ignored) and every wait has a
timeout, so no test here can hang.  The panel is checked on a tiny terminal emulator fed with
what rich wrote (in-process) and, where tmux exists, on a real terminal.
"""

from __future__ import annotations

import io
import os
import re
import select
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from rich.console import Console

from armctl.core.job import RunView
from armctl.script import compile_text
from armctl.ui.run_job import _Display

ARMCTL = [sys.executable, "-m", "armctl"]
ROOT = Path(__file__).resolve().parents[1]
WAIT_S = 20  # upper bound for any one wait; a healthy run takes a fraction of it
ENV = {key: value for key, value in os.environ.items() if key != "ARMCTL_PORT"}


def _default_sigint():
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _spawn(arguments, env=ENV, **kwargs):
    return subprocess.Popen([*ARMCTL, *arguments], preexec_fn=_default_sigint, env=env, cwd=ROOT, **kwargs)


def _interrupt(process, timeout_s=WAIT_S) -> int:
    process.send_signal(signal.SIGINT)
    try:
        return process.wait(timeout=timeout_s)
    finally:
        process.kill()


@pytest.mark.parametrize("arguments", [["sim", "--pty"], ["sim", "--tcp", "0"]], ids=["pty", "tcp"])
def test_sim_exits_130_on_ctrl_c(arguments):
    if arguments[-1] == "0":  # --tcp needs a port number: take a free one
        import socket

        with socket.socket() as probe:
            probe.bind(("127.0.0.1", 0))
            arguments = [*arguments[:-1], str(probe.getsockname()[1])]
    process = _spawn(arguments, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        ready = _readline(process.stdout)
        assert "(Ctrl-C to stop)" in ready, ready
        code = _interrupt(process)
        err = process.stderr.read()
    finally:
        process.kill()
    assert code == 130, err
    assert err.splitlines()[-1] == "armctl: interrupted" and "Traceback" not in err


def test_status_watch_plain_lines_exits_130_on_ctrl_c():
    process = _spawn(["status", "--watch", "--port", "sim://?speed=20"], stdout=subprocess.PIPE,
                     stderr=subprocess.PIPE, text=True)
    try:
        first = _readline(process.stdout)
        assert first.startswith("xyz="), first
        code = _interrupt(process)
        err = process.stderr.read()
    finally:
        process.kill()
    assert code == 130, err
    assert "Traceback" not in err


def test_status_watch_live_panel_exits_130_with_the_cursor_shown_again():
    """On a terminal (a pty here) the live view hides the cursor; Ctrl-C must show it again."""
    master, slave = os.openpty()
    try:
        process = _spawn(["status", "--watch", "--port", "sim://?speed=20"], stdin=slave, stdout=slave, stderr=slave,
                         env={**ENV, "TERM": "xterm-256color", "COLUMNS": "120", "LINES": "40"})
    finally:
        os.close(slave)
    output = b""
    try:
        output += _read_until(master, b"armctl status")
        process.send_signal(signal.SIGINT)
        code = process.wait(timeout=WAIT_S)
        output += _read_until(master, None)
    finally:
        process.kill()
        os.close(master)
    text = output.decode("utf-8", "replace")
    assert code == 130, text[-500:]
    assert "\x1b[?25l" in text  # the live view did hide it
    assert text.rfind("\x1b[?25h") > text.rfind("\x1b[?25l")  # and showed it again
    assert "armctl: interrupted" in text and "Traceback" not in text


def _readline(stream) -> str:
    ready, _, _ = select.select([stream], [], [], WAIT_S)
    assert ready, "no output within the wait bound"
    return stream.readline()


def _read_until(fd: int, marker: bytes | None) -> bytes:
    """Read the pty until ``marker`` shows (None: until the child closes it), within WAIT_S."""
    data = b""
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        ready, _, _ = select.select([fd], [], [], 0.1)
        if not ready:
            continue
        try:
            chunk = os.read(fd, 65536)
        except OSError:  # EIO: every holder of the slave has closed it
            return data
        if not chunk:
            return data
        data += chunk
        if marker is not None and marker in data:
            return data
    if marker is None:
        return data
    raise AssertionError(f"{marker!r} did not appear within {WAIT_S} s: {data[-300:]!r}")


# --- the run panel and a message printed while it is live ----------------------------------------

_CONTROL = re.compile(r"\x1b\[(\??)(\d*)([A-Za-z])|\r|\n")


def screen(raw: str, width: int = 100) -> list[str]:
    """What a terminal shows after ``raw``, for the few controls rich's Live uses: CR, LF,
    erase line (ESC[2K), cursor up (ESC[nA); colours and cursor visibility are ignored."""
    rows: list[list[str]] = [[]]
    row = col = 0
    position = 0
    for match in _CONTROL.finditer(raw):
        for char in raw[position : match.start()]:
            line = rows[row]
            line.extend(" " * (col - len(line) + 1))
            line[col] = char
            col += 1
        position = match.end()
        token = match.group(0)
        if token == "\r":
            col = 0
        elif token == "\n":
            row, col = row + 1, 0
            if row == len(rows):
                rows.append([])
        elif match.group(3) == "K" and match.group(2) == "2":
            rows[row] = []
        elif match.group(3) == "A":
            row = max(0, row - int(match.group(2) or 1))
    return ["".join(line).rstrip() for line in rows]


def _view(line: int, outcome: str = "running") -> RunView:
    statements = list(compile_text("G1 X200 Y0 Z150 A180 B0 C0 S1000 F3000\nG1 Z100\nG1 Z60\n", "job.txt"))
    return RunView(total_frames=3, estimated_job_s=10.0, lead_s=2.0, capacity=190, total_lines=3, frames_sent=line,
                   last_sent=statements[line - 1], last_done=statements[0], outcome=outcome)


class _TerminalStderr(io.TextIOWrapper):
    """Like the real sys.stderr of a terminal: a text layer over a byte ``buffer``, which is
    what click.echo writes to, past rich's proxy of sys.stderr."""

    def __init__(self) -> None:
        super().__init__(io.BytesIO(), encoding="utf-8", write_through=True)

    def isatty(self) -> bool:
        return True

    def getvalue(self) -> str:
        return self.buffer.getvalue().decode()


def test_a_message_while_the_panel_is_live_leaves_one_panel(monkeypatch):
    stderr = _TerminalStderr()
    monkeypatch.setattr(sys, "stderr", stderr)
    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=100, height=50, color_system=None, legacy_windows=False)
    with _Display("armctl run job.txt", True, console=console) as display:
        display.update(_view(1))
        display.note("\narmctl: interrupted: no more frames are sent")
        display.update(_view(2, outcome="interrupted"))
    shown = [line for line in screen(out.getvalue()) if line]
    assert sum("armctl run job.txt" in line for line in shown) == 1, "\n".join(shown)
    assert shown[0] == "armctl: interrupted: no more frames are sent"  # above the panel, not lost
    assert shown[1].startswith("╭") and shown[-1].startswith("╰")
    assert any("last line sent    2  G1 Z100" in line for line in shown)
    assert stderr.getvalue() == ""  # nothing written past rich to the screen it owns


def test_the_screen_emulator_sees_a_raw_write_break_the_panel():
    """The emulator is sharp enough to see the original fault: a line written past the panel
    (the next draw, of the lines that changed, lands too low: a stale frames line stays)."""
    out = io.StringIO()
    console = Console(file=out, force_terminal=True, width=100, height=50, color_system=None, legacy_windows=False)
    with _Display("armctl run job.txt", True, console=console) as display:
        display.update(_view(1))
        out.write("\narmctl: interrupted\n")  # what click.echo(err=True) did on the same terminal
        display.update(_view(2, outcome="interrupted"))
    shown = [line for line in screen(out.getvalue()) if line]
    assert sum(line.startswith("│ frames") for line in shown) == 2


@pytest.mark.skipif(shutil.which("tmux") is None, reason="needs tmux")
def test_ctrl_c_during_run_on_a_real_terminal_leaves_one_panel(tmp_path):
    socket_name = f"armctl-test-{os.getpid()}"
    tmux = ["tmux", "-L", socket_name]
    done_marker = "EXIT="
    command = (f"{sys.executable} -m armctl run scripts/pick_and_place.txt --port 'sim://?speed=4'; "
               f"echo {done_marker}$?; sleep 60")
    env = {**ENV, "TERM": "xterm-256color"}
    subprocess.run([*tmux, "new-session", "-d", "-s", "t", "-x", "110", "-y", "45", command], cwd=ROOT, env=env,
                   check=True, timeout=WAIT_S)
    try:
        _wait_for_pane(tmux, "last line sent    1")  # the panel is up and a frame went out
        subprocess.run([*tmux, "send-keys", "-t", "t", "C-c"], check=True, timeout=WAIT_S)
        pane = _wait_for_pane(tmux, done_marker)
    finally:
        subprocess.run([*tmux, "kill-server"], timeout=WAIT_S, capture_output=True)
    assert f"{done_marker}130" in pane, pane
    assert pane.count("armctl run scripts/pick_and_place.txt ─") == 1, pane
    assert "armctl: interrupted: no more frames are sent" in pane
    assert "stopped: interrupted" in pane


def _wait_for_pane(tmux, text: str) -> str:
    deadline = time.monotonic() + WAIT_S
    pane = ""
    while time.monotonic() < deadline:
        pane = subprocess.run([*tmux, "capture-pane", "-t", "t", "-p", "-S", "-200"], capture_output=True, text=True,
                              timeout=WAIT_S).stdout
        if text in pane:
            return pane
        time.sleep(0.1)
    raise AssertionError(f"{text!r} never appeared:\n{pane}")


@pytest.mark.realtime
@pytest.mark.parametrize("stop_signal", [signal.SIGTERM, signal.SIGHUP], ids=["SIGTERM", "SIGHUP"])
def test_sigterm_or_sighup_mid_job_takes_the_ctrl_c_path(tmp_path, stop_signal):
    """timeout, systemd, a CI cancelling (SIGTERM) or a closed terminal (SIGHUP): the job stops
    as on Ctrl-C — abort sequence, summary, resume line (with the options that shaped the run) — exit 130."""
    log = tmp_path / "job.log"
    port = "sim://?speed=5"
    process = _spawn(["run", "scripts/pick_and_place.txt", "--port", port, "--no-live", "--lead", "1.5",
                      "--log", str(log)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        first = _readline(process.stdout)  # the first progress line: the job is streaming
        assert first.startswith("[0:00] frames"), first
        process.send_signal(stop_signal)
        code = process.wait(timeout=WAIT_S)
        out, err = process.stdout.read(), process.stderr.read()
    finally:
        process.kill()
    assert code == 130, err
    assert f"note: stopped by {stop_signal.name}" in err and "Traceback" not in err
    assert any('"abort": true' in line for line in log.read_text().splitlines())
    resume = next(line for line in out.splitlines() if line.startswith("resume with: "))
    assert resume.startswith("resume with: armctl run scripts/pick_and_place.txt --from-line ")
    assert f"--port '{port}'" in resume and "--lead 1.5" in resume
