"""``armctl run``'s live panel keys through a real pseudo-terminal, against a wall-clock simulator.

The command runs with a pty as its stdin/stdout (``--port sim://?speed=10``: ten seconds of
arm time a second, so a 30-move job takes about three; ``--log LOG``), keys are typed as a
keyboard would, and the checks read both the screen (the panel says "paused", the override)
and the log (every frame written and every status frame read, on the run's clock): no frame
written and the arm's reported position unchanged while it reported paused, the frames
written after ``+`` carry 110 % of the script's speed, and the job still ends ``done``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pytest

from armctl.core.protocol import LinearMove, PauseToggle, decode_command, decode_status
from test_jog_pty import JogOnPty  # the pty plumbing

pytestmark = pytest.mark.realtime  # ARMCTL_SKIP_REALTIME=1 skips these (tests/conftest.py)

SPEED_MM_MIN = 1200.0


def _job(path: Path) -> Path:
    lines = [f"G1 X200 Y0 Z250 A180 B0 C0 S1500 F{SPEED_MM_MIN:g}"]
    lines += [f"G1 X{200 + (k % 2) * 20} Y{2 * k}" for k in range(1, 31)]  # 30 moves of about a second
    path.write_text("\n".join(lines) + "\n")
    return path


class RunOnPty(JogOnPty):
    """``armctl run`` on a fresh pty (the pty plumbing is the jog tests')."""

    def command(self, port: str, args: tuple) -> list[str]:
        return [sys.executable, "-m", "armctl", "run", *args, "--port", port, "--log", str(self.log_path)]

    def wait_for(self, fragment: str, timeout_s: float = 10.0, after: int = 0) -> int:
        """Where ``fragment`` first appears in the screen after offset ``after``."""
        deadline = time.monotonic() + timeout_s
        while (found := self.text().find(fragment, after)) < 0:
            if time.monotonic() > deadline or self.proc.poll() is not None:
                raise AssertionError(f"{fragment!r} never appeared; screen ends with {self.text()[-1500:]!r}")
            time.sleep(0.01)
        return found


def test_pause_resume_and_feed_override_from_the_keyboard(tmp_path):
    run = RunOnPty(tmp_path, str(_job(tmp_path / "job.txt")), port="sim://?speed=10")
    try:
        run.wait_for("keys: space/p pause/resume")
        run.wait_for("frames ", after=0)
        time.sleep(0.4)  # a few moves in
        run.type(b" ")
        run.wait_for("paused", after=run.text().rfind("feed · state"))
        time.sleep(0.5)  # five seconds of arm time, paused
        run.type(b"+")
        run.wait_for("110 %")
        run.type(b"p")
        assert run.proc.wait(20) == 0, run.text()[-1500:]
        assert "finished: the arm finished the job" in run.text()
        # the summary says what the estimate did not assume (issue 26): the pause and the override
        assert "this job was paused " in run.text() and "ran at 110 % feed" in run.text(), run.text()[-1500:]
        assert run.terminal_restored()
    finally:
        run.close()

    records = run.records()
    toggles = [r for r in records if r["dir"] == "tx" and r.get("control")]
    assert [bytes.fromhex(r["hex"]) for r in toggles] == [PauseToggle().encode()] * 2
    pause_s, resume_s = toggles[0]["t"], toggles[1]["t"]
    reports = [(r["t"], decode_status(bytes.fromhex(r["hex"]))) for r in records if r["dir"] == "rx"]
    paused = [index for index, (t, frame) in enumerate(reports) if frame.KIND == 4 and frame.paused]
    assert paused, "the arm never reported paused"
    first, last = paused[0], paused[-1]  # in the order read (a burst read at once shares its time)
    assert reports[last][0] - reports[first][0] > 2.0  # arm time: it stayed paused while the keys waited
    # nothing of the job written from the pause key to the resume key
    job_frames = [r for r in records if r["dir"] == "tx" and "line" in r]
    assert not [r for r in job_frames if pause_s < r["t"] < resume_s]
    # the arm stood still while it reported paused
    positions = {frame.fields()["x_mm"] for t, frame in reports[first:last] if frame.KIND == 0}
    assert len(positions) == 1
    # frames written after the resume carry 110 % of the script's speed, the ones before 100 %
    speeds = [(r["t"], decode_command(bytes.fromhex(r["hex"]))) for r in job_frames]
    assert all(isinstance(c, LinearMove) for _, c in speeds)
    before = {c.speed_mm_min for t, c in speeds if t < pause_s}
    after = {c.speed_mm_min for t, c in speeds if t > resume_s}
    assert before == {SPEED_MM_MIN} and after == {SPEED_MM_MIN * 1.1}
    assert len(job_frames) == 31


def test_the_stop_key_takes_the_ctrl_c_path(tmp_path):
    run = RunOnPty(tmp_path, str(_job(tmp_path / "job.txt")), port="sim://?speed=10")
    try:
        run.wait_for("keys: space/p pause/resume")
        time.sleep(0.3)
        run.type(b"s")
        assert run.proc.wait(20) == 130, run.text()[-1500:]
        assert run.terminal_restored()
    finally:
        run.close()
    assert "resume with: armctl run" in run.text()
    aborts = [r for r in run.records() if r["dir"] == "tx" and r.get("abort")]
    assert [bytes.fromhex(r["hex"]) for r in aborts] == [PauseToggle().encode()]  # --abort pause, once
