"""An adversarial review of crash survival and resume (``run --log``, ``run --resume LOG``), as
users meet it: each fault found, its reproduction kept as a test, and the sweeps that found nothing.

1. A log whose run was killed before its first frame has no job record; its refusal told the
   user to "run the job from its start" — wrong when that run was itself a resume (or started
   at a --from-line): the lines the earlier run executed would run twice.  Now it names the way
   the run was started (the log it resumed, its --from-line).  Fresh process, real SIGKILL.
   The job record itself torn by the crash was "not a `run --log` file": now the same refusal.
2. A bit flipped in the line break of the log's last record made a complete, intact record
   look like the crash's torn last line: ignored, so the frame it records — written, and run
   by the arm — was resumed again (a PWM-only line, or the first line, ran twice).  A torn line
   is a strict prefix of a record: an intact record followed by anything but the NUL bytes a
   file system may leave after a cut is damage, refused (exit 1).
3. ``--resume LOG`` of a job still running (the log locked by the armctl writing it) read a
   log that was still growing: through a port that serves one client after another
   (``armctl sim --tcp``, a network serial server) it waited for the job to end, then resumed
   at a line the still-running job had already sent: lines ran twice.  Now refused, exit 2,
   nothing sent.  And two resumes of one log at once (each with a --log of its own) both
   resumed at the same line, through ``armctl sim --tcp``: a resume now locks the log it reads.
4. A resume that continues at the first line of a repeat block (no job starts inside one, as
   ``--from-line``: documented) said only "the log and the arm's report prove every line before
   it ran", while the passes already done ran again (9 frames of a 26-frame job, through
   ``armctl sim --pty``): it now names the lines that run again.
5. The log's directory entry was never fsynced: a power cut could leave no log at all for
   --resume, though every record in it was.  Now fsynced once, with the first durable record.
6. Sweeps that found nothing: a crash log cut anywhere (densely: see the test), and with each of the 8 bits
   of every byte flipped (but 2's), is refused (an ``ArmctlError``) or resumed at exactly the right line.
"""

from __future__ import annotations

import io

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from armctl.core.joblog import read_resume_lines
from armctl.errors import ArmctlError, ResumeRefused

from journal_crash import make_crash, pty_arm

ARMCTL = [sys.executable, "-m", "armctl"]

# a move, a PWM-only change (the arm does not move), a move back, a PWM-only change again
PWM = """\
G1 X220 Y0 Z200 A180 B0 C0 S1000 F6000
G1 X260
G1 S2000
G1 X220
G1 S1000
"""


def _env() -> dict:
    return {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}


@pytest.fixture(scope="module")
def pwm_crashes(tmp_path_factory):
    """The PWM script crashed after each of its frames (virtual clock, the arm runs out its queue)."""
    folder = tmp_path_factory.mktemp("pwm")
    script = folder / "pwm.txt"
    script.write_text(PWM)
    return [make_crash(script, n, folder / f"crash{n}.log") for n in range(1, 6)]


def _decide(crash, log: bytes):
    """The line a resume of ``log`` continues at (None: nothing left), or the refusal."""
    point = read_resume_lines(io.StringIO(log.decode("utf-8", errors="replace")), crash.script.name, crash.script.read_bytes())
    return point.line_for(*crash.rest)


def _sound(crash, log: bytes) -> str:
    """"refused" or "resumed": never any other exception, never a line run twice or skipped."""
    try:
        line = _decide(crash, log)
    except ArmctlError:
        return "refused"
    assert crash.correct(line), f"resumed at line {line}: a line runs twice or is skipped"
    return "resumed"


# --- 1. a log with no job record: what to do ----------------------------------------------------


def test_a_log_without_a_job_record_does_not_send_the_user_back_to_line_1():
    from armctl.host.resume_words import CLI

    with pytest.raises(ResumeRefused) as refused:  # (as armctl run's --resume reads it: in its words)
        read_resume_lines(io.StringIO(""), "job.txt", b"G1 X200\n", words=CLI)
    message = str(refused.value)
    assert "run the job from its start" not in message
    assert "--resume" in message and "--from-line" in message  # the ways that run may have been started


def test_a_job_record_torn_by_the_crash_is_no_job_record_not_another_file(pwm_crashes):
    """The crash's cut inside the job record (written and fsynced before the first frame): the
    refusal said "line 1 is not an intact journal record: not a `run --log` file" — and so
    after an intact record (the pause toggle a run sends to an arm it finds paused)."""
    from armctl.core.joblog import seal

    crash = pwm_crashes[0]
    job = crash.log[:crash.log.index(b"\n")]
    toggle = (seal({"t": 0.0, "dir": "tx", "hex": "ee" + "00" * 46 + "ef", "resume": True}, 0) + "\n").encode()
    for before in (b"", toggle):
        for end in range(1, len(job)):
            with pytest.raises(ResumeRefused, match="it has no job record") as refused:
                _decide(crash, before + job[:end])
            assert "not a `run --log` file" not in str(refused.value)
    with pytest.raises(ResumeRefused, match="not a `run --log` file"):  # a file that is no log still says so
        _decide(crash, b"G1 X200")


# --- 2. the line break of the last record flipped -----------------------------------------------

FLIPS = [bytes([0x0A ^ (1 << bit)]) for bit in range(8)]  # every one-bit flip of "\n"


@pytest.mark.parametrize("n", range(1, 6))
def test_a_flipped_line_break_after_the_last_record_is_not_the_crashs_cut(pwm_crashes, n):
    crash = pwm_crashes[n - 1]
    durable = crash.log[:crash.durable_end]  # up to the record of the last frame written, with its line break
    assert _sound(crash, durable) in ("resumed", "refused")
    for flip in FLIPS:
        assert _sound(crash, durable[:-1] + flip) == "refused", flip


def test_the_crashs_cut_after_a_whole_record_still_resumes(pwm_crashes):
    """What a cut may leave after the last durable record: nothing, a torn next record, or NUL
    bytes (blocks a file system allocated but never wrote) — still the crash's cut."""
    crash = pwm_crashes[0]
    durable = crash.log[:crash.durable_end]
    rest = crash.log[crash.durable_end:]
    assert _sound(crash, durable) == "resumed"
    assert _sound(crash, durable + rest[:25]) == "resumed"
    assert _sound(crash, durable + b"\0" * 300) == "resumed"
    # a record whose own line break never reached the disk: not durable, so its frame was not written
    assert _sound(crash, durable + rest[:rest.index(b"\n")]) == "resumed"
    assert _sound(crash, durable + rest[:rest.index(b"\n")] + b"\0\0") == "resumed"


# --- 3. a log another armctl is still writing ---------------------------------------------------


def _hold_lock(log: Path):
    """A process that holds ``log``'s lock as ``armctl run --log`` does while its job runs."""
    holder = subprocess.Popen([sys.executable, "-c", (
        "import fcntl, sys, time\n"
        f"log = open({str(log)!r}, 'a')\n"
        "fcntl.flock(log.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)\n"
        "print('locked', flush=True)\n"
        "time.sleep(60)\n")], stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline() == "locked\n"
    return holder


@pytest.mark.skipif(sys.platform == "win32", reason="no flock")
def test_resuming_a_log_whose_job_still_runs_is_refused_before_the_port(tmp_path, pwm_crashes):
    crash = pwm_crashes[2]
    log = tmp_path / "running.log"
    log.write_bytes(crash.log)
    holder = _hold_lock(log)
    try:
        done = subprocess.run([*ARMCTL, "run", str(crash.script), "--port", "sim://?clock=virtual", "--no-live",
                               "--resume", str(log)], capture_output=True, text=True, timeout=60, cwd=tmp_path,
                              env=_env())
        from armctl import Arm

        with Arm.open(port="sim://?clock=virtual") as arm:  # the API reads the resume log the same way
            with pytest.raises(ResumeRefused, match="still running"):
                arm.run(crash.script, resume=log)
            assert len(arm._link.port.model.frames_received) == 0
    finally:
        holder.kill()
        holder.wait()
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    assert "still running" in done.stderr and "using the built-in simulator" not in done.stderr, done.stderr
    # once that job ended (its lock gone), the same resume goes on
    again = subprocess.run([*ARMCTL, "run", str(crash.script), "--port", "sim://?clock=virtual", "--no-live",
                            "--resume", str(log)], capture_output=True, text=True, timeout=60, cwd=tmp_path, env=_env())
    assert "still running" not in again.stderr and "Traceback" not in again.stderr, again.stderr


@pytest.mark.skipif(sys.platform == "win32", reason="no flock")
def test_a_log_being_resumed_cannot_be_resumed_again_at_the_same_time(tmp_path, pwm_crashes):
    """Two ``--resume LOG`` at once (each with a --log of its own) both read LOG and decided
    alike: through ``armctl sim --tcp`` (one client after another) the second waited for the
    first to finish, found the arm where LOG's last frame leaves it again (a job that comes back
    to a point), and sent the same lines a second time.  A resume now holds LOG locked while it
    runs, as a run holds its --log: the second is refused, exit 2, nothing sent."""
    from armctl import Arm
    from armctl.host.log_lock import journal_in_use

    crash = pwm_crashes[0]
    log = tmp_path / "crash.log"
    log.write_bytes(crash.log)
    seen: list[bool] = []
    with Arm.open(port="sim://?clock=virtual") as arm:  # the arm where crash 1 left its: the resume runs
        arm.move(x=220, y=0, z=200, a=180, b=0, c=0, f=6000)
        arm.run(crash.script, resume=log, on_progress=lambda progress: seen.append(journal_in_use(str(log))))
    assert seen and all(seen), seen  # locked while the resume ran
    assert not journal_in_use(str(log))
    # the installed command: a second resume while one holds the log
    holder = subprocess.Popen([sys.executable, "-c", (
        "import sys, time\n"
        "from armctl.host.log_lock import resume_claim\n"
        f"with resume_claim({str(log)!r}):\n"
        "    print('claimed', flush=True)\n"
        "    time.sleep(60)\n")], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline() == "claimed\n"
        done = subprocess.run([*ARMCTL, "run", str(crash.script), "--port", "sim://?clock=virtual", "--no-live",
                               "--resume", str(log), "--log", str(tmp_path / "second.log")], capture_output=True,
                              text=True, timeout=60, cwd=tmp_path, env=_env())
    finally:
        holder.kill()
        holder.wait()
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert "resuming it" in done.stderr and "using the built-in simulator" not in done.stderr, done.stderr


# --- 4. a resume that starts a repeat block again says so -------------------------------------

LOOP = """\
G1 X220 Y0 Z200 A180 B0 C0 S1000 F3000
O<a> repeat [6]
  G1 X240 Y0
  G1 X240 Y20
  G1 X220 Y20
  G1 X220 Y0
O<a> endrepeat
G1 X260 Y0
"""


@pytest.mark.parametrize("n", [1, 2, 10, 13])
def test_a_resume_that_starts_a_repeat_block_again_says_which_lines_run_again(tmp_path, n):
    """The job killed in pass 3 of its block (after 10 frames): the resume continued at line 2,
    the block's first line — as documented — but said only "the log and the arm's report prove
    every line before it ran"; 9 frames of lines 3-6 then ran a second time, unsaid."""
    from armctl import Arm
    from armctl.host.arm_worker import JobObserver

    from journal_crash import crash_into, job_commands, ran

    script, log = tmp_path / "loop.txt", tmp_path / "crash.log"
    script.write_text(LOOP)
    notes: list[str] = []

    class Notes(JobObserver):
        def note(self, text: str) -> None:
            notes.append(text)

    with Arm.open(port="sim://?clock=virtual") as arm:
        crash_into(arm, script, n, log)
        before = ran(arm)
        result = arm.run(script, resume=log, observer=Notes())
        after = ran(arm)
    line = int(re.search(r"resuming \S+ at line (\d+)", " ".join(notes)).group(1))
    assert after == before + job_commands(script, line) and result.frames_sent == len(job_commands(script, line))
    said = " ".join(notes)
    assert line == 2
    if n == 1:  # before the block: nothing runs twice, nothing said
        assert "run again" not in said, said
    else:
        assert f"lines 2–{3 if n == 2 else 6} of the passes already done run again" in said, said


# --- 5. the log's own directory entry is durable before the first frame --------------------------


def test_a_new_logs_directory_is_fsynced_before_its_first_durable_record(tmp_path, monkeypatch):
    """A log the run creates exists after a power cut only once its directory entry is durable
    (POSIX: fsync the directory; SQLite and PostgreSQL do): the records were fsynced, the
    directory never was, so the crash could leave no log at all — or the empty file of an earlier
    run — for --resume to read.  The directory is now fsynced once, with the first durable record."""
    import stat

    from armctl.host.jobflow import JournalFile

    synced: list[str] = []
    real_fsync = os.fsync

    def fsync(descriptor):
        synced.append("dir" if stat.S_ISDIR(os.fstat(descriptor).st_mode) else "file")
        real_fsync(descriptor)

    monkeypatch.setattr(os, "fsync", fsync)
    with open(tmp_path / "new.log", "w", encoding="utf-8") as file:
        journal = JournalFile(file, sync=True)
        journal.append({"dir": "rx", "hex": "00"})
        assert synced == []  # a status record is not made durable by itself
        journal.append({"dir": "job"}, durable=True)
        assert sorted(synced) == ["dir", "file"]
        journal.append({"dir": "tx", "hex": "00"}, durable=True)
        assert sorted(synced) == ["dir", "file", "file"]  # once: the entry does not change again
    synced.clear()
    with open(tmp_path / "virtual.log", "w", encoding="utf-8") as file:  # a virtual clock: flushed only
        JournalFile(file, sync=False).append({"dir": "job"}, durable=True)
    assert synced == []


# --- 6. sweeps: cuts anywhere, every byte flipped ------------------------------------------------


def test_a_crash_log_cut_anywhere_is_refused_or_resumed_exactly(pwm_crashes):
    # Cut at every byte up to the end of the first record after the last durable one, at every
    # line break and the two bytes on each side of it, and at every 13th byte between (13 is
    # prime to the records' lengths, so the cuts fall at every place in a record over the log).
    # Every byte everywhere read each prefix whole: 18,000 reads, 7.5 s of CPU alone and 19 s
    # in the README's suite, which its 150 s budget could not carry; the status records after
    # the last durable one are alike, and these cuts meet each kind of place in them.
    outcomes = set()
    for crash in (pwm_crashes[1], pwm_crashes[3]):
        log = crash.log
        every_byte_to = log.index(b"\n", crash.durable_end) + 1 if b"\n" in log[crash.durable_end:] else len(log)
        breaks = {i + d for i, byte in enumerate(log) if byte == 0x0A for d in (-2, -1, 0, 1, 2)}
        for end in range(len(log) + 1):
            if end > every_byte_to and end % 13 and end not in breaks and end != len(log):
                continue
            cut = log[:end]
            if end < crash.durable_end:  # a cut before the record of a frame written: not what a crash leaves
                try:
                    _decide(crash, cut)
                except ArmctlError:
                    pass
                continue
            outcomes.add(_sound(crash, cut))
    assert outcomes == {"resumed"}


def test_a_crash_log_with_any_bit_flipped_is_refused_or_resumed_exactly(pwm_crashes):
    """Every one of the 8 bits of every byte of the durable log (before the fix of 2, the 8 flips
    of its last byte resumed a frame the arm had run)."""
    outcomes = set()
    for crash in (pwm_crashes[0], pwm_crashes[2]):
        log = crash.log[:crash.durable_end]
        for offset in range(len(log)):
            for bit in range(8):
                flipped = bytearray(log)
                flipped[offset] ^= 1 << bit
                outcomes.add(_sound(crash, bytes(flipped)))
    assert "refused" in outcomes


# --- 1 again, as a user meets it: real SIGKILLs, an arm in another process -----------------------

JOB = "".join(f"G1 X{220 + 4 * i} Y{(i % 3) * 5} Z200{' A180 B0 C0 S1000 F3000' if i == 0 else ''}\n" for i in range(24))


def _frames(log: Path) -> list[str]:
    """The hex of every frame a --log records as written (its record, durable before the frame)."""
    frames = []
    for line in log.read_text(errors="replace").split("\n") if log.exists() else ():
        try:
            record = json.loads(line)
        except ValueError:
            continue
        if isinstance(record, dict) and record.get("dir") == "tx":
            frames.append(record["hex"])
    return frames


def _wait(condition, timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.005)
    return False


@pytest.mark.realtime
@pytest.mark.timeout(120)
@pytest.mark.skipif(sys.platform == "win32", reason="armctl sim --pty needs a POSIX terminal")
def test_kill_9_twice_then_the_advised_resume_runs_every_line_once(tmp_path):
    """``armctl sim --pty --stats`` in a process of its own; ``armctl run --log j1`` killed with
    SIGKILL mid-stream; its ``--resume j1 --log j2`` killed with SIGKILL while it waits for the
    arm to come to rest (nothing sent).  ``--resume j2`` is refused, exit 2, and says to resume
    j1 (not to run the job from its start); ``--resume j1`` then finishes the job, and the arm's
    own record holds every frame of the job exactly once."""
    from armctl.core.protocol import decode_command
    from armctl.script.files import read_script

    script, stats = tmp_path / "job.txt", tmp_path / "stats.json"
    script.write_text(JOB)
    profile = tmp_path / "arm.toml"  # the FIFO size as `armctl probe --write` keeps it: `finished` is proven
    profile.write_text("[connector]\nfifo_frames = 200\n")
    j1, j2, j3 = tmp_path / "j1.log", tmp_path / "j2.log", tmp_path / "j3.log"
    with pty_arm("--stats", str(stats), env=_env()) as pty:
        def run(*args, **kwargs):
            return [*ARMCTL, "run", str(script), "--port", pty, "--no-live", "--profile", str(profile), *args]

        first = subprocess.Popen(run("--log", str(j1)), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                 cwd=tmp_path, env=_env())
        assert _wait(lambda: len(_frames(j1)) >= 8, 60), "the first run wrote no 8 frames"
        first.kill()
        first.wait(10)
        resume = subprocess.Popen(run("--resume", str(j1), "--log", str(j2)), stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL, cwd=tmp_path, env=_env())
        assert _wait(j2.exists, 30)  # its log is open: now it reads the arm and waits for it to rest
        resume.kill()
        resume.wait(10)
        assert _frames(j2) == []  # (it sends nothing before the arm is at rest: at least 0.6 s)

        advised = subprocess.run(run("--resume", str(j2), "--log", str(j3)), capture_output=True, text=True,
                                 timeout=60, cwd=tmp_path, env=_env())
        assert advised.returncode == 2 and "Traceback" not in advised.stderr, advised.stderr
        assert "run the job from its start" not in advised.stderr and "--resume" in advised.stderr, advised.stderr

        last = subprocess.run(run("--resume", str(j1), "--log", str(j3)), capture_output=True, text=True,
                              timeout=90, cwd=tmp_path, env=_env())
        assert last.returncode == 0, last.stdout + last.stderr
        assert "finished" in last.stdout
    seen = json.loads(stats.read_text())
    assert seen["complete"] and seen["dropped"] == 0
    later = _frames(j3)  # j2 holds no frame; j1's last record may be of a frame never written
    received = len(seen["frames"])
    written = _frames(j1)[: received - len(later)] + later
    assert len(written) == received
    executed = [decode_command(bytes.fromhex(written[index])) for index, _, _, outcome in seen["executions"]
                if outcome not in ("skipped", "ignored")]
    assert executed == [statement.command for statement in read_script(str(script)).compile()]
