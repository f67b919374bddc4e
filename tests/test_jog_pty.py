"""``armctl jog`` through a real pseudo-terminal against the simulator, in real time.

Each test spawns the command with a pty as its stdin/stdout (``--port sim:// --log LOG``), types
key bytes the way a keyboard's auto-repeat does (a press, then repeats every 33 ms after a
400 ms delay — shorter than jog's 500 ms, as it should be configured), and reads the log: every
key jog read and every frame it wrote, on jog's own clock.  So the latencies checked are the
ones the arm would see.  The tests are few and short (each under 5 s); they need no custom
marker: deselect them with ``-k "not pty"`` or ARMCTL_SKIP_REALTIME=1.
"""

from __future__ import annotations

import fcntl
import json
import os
import select
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
from pathlib import Path

import pytest

from armctl.core.protocol import JointMove, Joystick, decode_command, decode_status

pytestmark = pytest.mark.realtime  # ARMCTL_SKIP_REALTIME=1 skips these (tests/conftest.py)

REPEAT_S = 0.033
KEYBOARD_DELAY_S = 0.4
NEUTRAL_AFTER_REPEAT_S = 0.150  # the bound
TAP_LIMIT_S = 0.5  # jog's default initial delay


def _jog_command() -> list[str]:
    from armctl.ui.cli import main

    if "jog" in main.commands:  # registered by the lead in armctl/ui/cli.py
        return [str(Path(sys.executable).with_name("armctl")), "jog"]
    return [sys.executable, "-m", "armctl.jog"]


class JogOnPty:
    """``armctl jog`` running on a fresh pty; its screen collected by a thread."""

    def __init__(self, tmp_path: Path, *args: str, port: str = "sim://") -> None:
        self.log_path = tmp_path / "jog.log"
        self.master, self.slave = os.openpty()
        fcntl.ioctl(self.slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 100, 0, 0))
        self.saved = termios.tcgetattr(self.slave)
        env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
        self.proc = subprocess.Popen(
            self.command(port, args),
            stdin=self.slave, stdout=self.slave, stderr=self.slave, cwd=tmp_path, env=env, start_new_session=True,
        )
        self.screen = bytearray()
        self._stop = threading.Event()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def command(self, port: str, args: tuple) -> list[str]:
        return [*_jog_command(), "--port", port, "--log", str(self.log_path), *args]

    def _read(self) -> None:
        # select first: a thread blocked in read() would keep the master open after close().
        while not self._stop.is_set():
            if not select.select([self.master], [], [], 0.01)[0]:
                continue
            try:
                data = os.read(self.master, 4096)
            except OSError:
                return
            if not data:
                return
            self.screen += data

    def hang_up(self) -> None:
        """Close the terminal's master side, like a terminal window being closed."""
        self._stop.set()
        self._reader.join()
        os.close(self.master)

    def text(self) -> str:
        return self.screen.decode("utf-8", "replace")

    def wait_for(self, fragment: str, timeout_s: float = 5.0) -> None:
        deadline = time.monotonic() + timeout_s
        while fragment not in self.text():
            if time.monotonic() > deadline or self.proc.poll() is not None:
                raise AssertionError(f"{fragment!r} never appeared; screen ends with {self.text()[-800:]!r}")
            time.sleep(0.01)

    def ready(self) -> "JogOnPty":
        self.wait_for("keys (")  # the panel is up: raw mode is on
        return self

    def type(self, data: bytes) -> None:
        os.write(self.master, data)

    def hold(self, key: bytes, seconds: float) -> None:
        """Press ``key`` and keep it down: auto-repeat after 400 ms, every 33 ms."""
        self.type(key)
        time.sleep(KEYBOARD_DELAY_S)
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.type(key)
            time.sleep(REPEAT_S)

    def exit_code(self, timeout_s: float = 5.0) -> int:
        return self.proc.wait(timeout_s)

    def records(self) -> list[dict]:
        return [json.loads(line) for line in self.log_path.read_text().splitlines() if line.strip()]

    def events(self) -> list[tuple[float, str, object]]:
        """(t, "key", name) and (t, "tx", command) in log order."""
        out = []
        for record in self.records():
            if record["dir"] == "key":
                out.append((record["t"], "key", record["key"]))
            elif record["dir"] == "tx":
                out.append((record["t"], "tx", decode_command(bytes.fromhex(record["hex"]))))
        return out

    def frames(self) -> list[tuple[float, object]]:
        return [(t, c) for t, kind, c in self.events() if kind == "tx"]

    def reported_joints(self, kind: int = 1) -> list[tuple[float, ...]]:
        return [tuple(decode_status(bytes.fromhex(r["hex"])).fields().values())
                for r in self.records() if r["dir"] == "rx" and r["kind"] == kind]

    def terminal_restored(self) -> bool:
        return termios.tcgetattr(self.slave) == self.saved

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        self._stop.set()
        self._reader.join()
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass


@pytest.fixture
def spawn(tmp_path):
    started = []

    def start(*args, **kwargs) -> JogOnPty:
        jog = JogOnPty(tmp_path, *args, **kwargs)
        started.append(jog)
        return jog

    yield start
    for jog in started:
        jog.close()


def _last_key(events, name: str, before: float) -> float:
    return max(t for t, kind, value in events if kind == "key" and value == name and t <= before)


LEASE_AFTER_PRESS_S = 0.5 - 0.020  # jog's tap lease (initial delay less its wake margin)
LEASE_AFTER_REPEAT_S = 0.1 - 0.020  # once repeats flow (repeat gap less the wake margin)


def motions(events, keys: dict[str, int], stopped_by: str | None = None) -> list[int]:
    """Check the dead-man contract on jog's own clock and return the axis of each motion.

    A busy machine can delay the test's typing (a "held" key whose repeats pause longer than
    the lease): jog must then stop and start again — that is the dead-man switch working — so
    the contract is checked against the keys jog actually read, not against the keys we meant:
    - frames alternate: one non-neutral value, then the neutral of the same axis;
    - once repeats flowed, the neutral comes within 150 ms of the last one; a motion of one key
      and no repeat (a tap) lasts no longer than the tap limit;
    - a neutral goes out only once the lease of the last key has run out (no stop while keys
      flow), except the last one when ``stopped_by`` names the key (or event) that stopped it.
    """
    frames = [(t, c) for t, kind, c in events if kind == "tx"]
    assert len(frames) % 2 == 0 and frames, frames
    axes = []
    for index in range(0, len(frames), 2):
        (t_on, on), (t_off, off) = frames[index], frames[index + 1]
        assert isinstance(on, Joystick) and isinstance(off, Joystick) and on.axis == off.axis, (on, off)
        assert any(v != 128 for v in on.values) and all(v == 128 for v in off.values), (on, off)
        name = next(k for k, axis in keys.items() if axis == on.axis)
        pressed = [t for t, kind, value in events if kind == "key" and value == name and t <= t_off]
        during = [t for t in pressed if t >= _last_key(events, name, t_on)]  # this motion's keys
        if len(during) > 1:  # repeats flowed
            assert t_off - during[-1] <= NEUTRAL_AFTER_REPEAT_S, (t_off - during[-1], name)
        else:  # a tap
            assert t_off - t_on <= TAP_LIMIT_S, (t_off - t_on, name)
        last_frame = index + 2 == len(frames)
        if not (last_frame and stopped_by):
            lease = LEASE_AFTER_PRESS_S if len(during) == 1 else LEASE_AFTER_REPEAT_S
            assert t_off - during[-1] >= lease - 0.005, (t_off - during[-1], lease, name)
        axes.append(on.axis)
    return axes


def _collapse(axes: list[int]) -> list[int]:
    """One entry per run of motions of the same axis (a delayed typist splits one hold)."""
    return [axis for k, axis in enumerate(axes) if k == 0 or axes[k - 1] != axis]


def test_pty_hold_stops_within_150ms_of_the_last_repeat_and_a_tap_within_the_delay(spawn):
    jog = spawn().ready()
    jog.hold(b"q", 0.6)  # joint 1 +
    time.sleep(0.3)
    jog.type(b"e")  # a tap on joint 3 +
    time.sleep(0.8)
    jog.type(b"x")
    assert jog.exit_code() == 0
    assert jog.terminal_restored()

    events = jog.events()
    axes = motions(events, {"q": 0, "e": 2})
    assert _collapse(axes) == [0, 2] and axes[-1] == 2 and axes.count(2) == 1
    frames = jog.frames()
    t_off = frames[-3][0]  # the neutral that ended the hold of q
    after_repeat = t_off - _last_key(events, "q", t_off)
    tap_s = frames[-1][0] - frames[-2][0]
    print(f"\nneutral {after_repeat * 1000:.1f} ms after the last repeat; a tap moved {tap_s * 1000:.1f} ms"
          f"{'' if len(axes) == 2 else f' (the held key was read as {len(axes) - 1} holds)'}")
    assert "quit" in jog.text()


def test_pty_ctrl_c_while_moving_sends_the_neutral_at_once_and_exits_130(spawn):
    jog = spawn().ready()
    jog.hold(b"w", 0.3)
    jog.type(b"\x03")
    assert jog.exit_code() == 130
    assert jog.terminal_restored()
    events = jog.events()
    frames = jog.frames()
    assert _collapse(motions(events, {"w": 1}, stopped_by="ctrl-c")) == [1]
    assert frames[-1][1] == Joystick(1, (128,))
    ctrl_c = _last_key(events, "ctrl-c", frames[-1][0])
    assert frames[-1][0] - ctrl_c <= 0.05  # at once: the neutral is the first thing jog does with it
    print(f"\nneutral {(frames[-1][0] - ctrl_c) * 1000:.1f} ms after Ctrl-C was read")


def test_pty_escape_quits_and_stops_a_linear_jog(spawn):
    jog = spawn("--mode", "linear").ready()
    jog.hold(b"\x1b[A", 0.3)  # arrow up: X+
    jog.type(b"\x1b")  # a lone Esc: a key once 50 ms have passed with nothing after it
    assert jog.exit_code() == 0
    assert jog.terminal_restored()
    frames = jog.frames()
    assert _collapse(motions(jog.events(), {"up": 100}, stopped_by="esc")) == [100]
    assert frames[0][1] == Joystick(100, (152, 128, 128)) and frames[-1][1] == Joystick(100, (128, 128, 128))


def test_pty_sigterm_while_moving_stops_the_arm_and_restores_the_terminal(spawn):
    jog = spawn().ready()
    jog.hold(b"r", 0.2)
    jog.proc.send_signal(signal.SIGTERM)
    assert jog.exit_code() == 1
    assert jog.terminal_restored()
    assert _collapse(motions(jog.events(), {"r": 3}, stopped_by="SIGTERM")) == [3]
    assert jog.frames()[-1][1] == Joystick(3, (128,))
    assert "SIGTERM" in jog.text()


def test_pty_terminal_gone_while_moving_sends_the_neutral_at_once(spawn):
    jog = spawn().ready()
    jog.hold(b"t", 0.2)
    jog.hang_up()
    assert jog.exit_code() == 1
    events = jog.events()
    frames = jog.frames()
    assert _collapse(motions(events, {"t": 4}, stopped_by="hang-up")) == [4]
    assert frames[-1][1] == Joystick(4, (128,))
    # The hang-up came about one repeat after the last key: well before the lease's end.
    after_repeat = frames[-1][0] - _last_key(events, "t", frames[-1][0])
    print(f"\nterminal gone: neutral {after_repeat * 1000:.1f} ms after the last repeat (hang-up ~33 ms after it)")
    notes = [r["text"] for r in jog.records() if r["dir"] == "note"]
    assert notes and "the terminal went away" in notes[-1]


def test_pty_step_mode_moves_by_the_increment_and_taught_poses_lint_clean_and_replay(spawn, tmp_path):
    record = tmp_path / "taught.txt"
    jog = spawn("--record", str(record)).ready()
    jog.type(b"\t")  # step mode
    jog.type(b"q")  # level 1: J1 + 1 deg
    time.sleep(0.8)
    jog.type(b"++")  # level 3: 10 deg
    jog.type(b"q")
    time.sleep(1.0)
    jog.type(b"\r")  # teach a G6
    time.sleep(0.4)
    jog.type(b"m\r")  # linear mode, teach a G1
    time.sleep(0.5)
    jog.type(b"x")
    assert jog.exit_code() == 0
    assert jog.terminal_restored()

    steps = [c for _, c in jog.frames() if isinstance(c, JointMove)]
    assert [s.j1_deg for s in steps] == [1.0, 11.0]
    assert jog.reported_joints()[-1][0] == pytest.approx(11.0)
    assert "2 poses recorded" in jog.text()

    lines = [line for line in record.read_text().splitlines() if not line.startswith(";")]
    assert lines[0].startswith("G6 J1=11 J2=0 J3=0 J4=0 J5=90 J6=0 S1500 F60 ; taught ")
    assert lines[1].startswith("G1 X") and " S1500 F3000 ; taught " in lines[1]

    from armctl.script import compile_file

    compilation = compile_file(record)
    assert len(list(compilation)) == 2
    assert compilation.finish() == []
    lint = pytest.importorskip("armctl.lint.command")
    from click.testing import CliRunner

    result = CliRunner().invoke(lint.lint, [str(record)])
    assert result.exit_code == 0, result.output

    armctl = str(Path(sys.executable).with_name("armctl"))
    replay = subprocess.run([armctl, "run", str(record), "--port", "sim://?clock=virtual", "--no-live"],
                            capture_output=True, text=True, cwd=tmp_path, timeout=20)
    assert replay.returncode == 0, replay.stdout + replay.stderr
    assert "finished: the arm finished the job" in replay.stdout


def test_pty_no_status_from_the_arm_refuses_to_jog(spawn):
    jog = spawn("--timeout", "0.3", port="loop://")
    assert jog.exit_code() == 1
    jog.wait_for("refusing to jog")
    assert jog.frames() == []
    assert jog.terminal_restored()


def test_stdin_not_a_terminal_is_a_usage_error(tmp_path):
    result = subprocess.run([*_jog_command(), "--port", "sim://"], stdin=subprocess.DEVNULL, capture_output=True,
                            text=True, cwd=tmp_path, timeout=20)
    assert result.returncode == 2
    assert "stdin is not a terminal" in result.stderr
    assert "Traceback" not in result.stderr


def test_pty_a_virtual_clock_simulator_is_refused_with_a_sentence(spawn):
    jog = spawn(port="sim://?clock=virtual")
    assert jog.exit_code() == 2
    jog.wait_for("jog runs in real time")
    assert not jog.log_path.exists() or jog.frames() == []
    assert jog.terminal_restored()
    assert "Traceback" not in jog.text()
