"""The journal of ``run --log`` as a write-ahead log (issue 22, Deliver 1; issue 21's ``--resume``
after a stop): each fault found, through the installed command in a fresh process and the API.

1. A frame's record is durable (flushed, fsynced) before the frame is written to the port; so
   a power cut cannot leave the log the issue resumed wrongly (scripts/joint_routine.txt, crash
   after 14 frames, the log up to its 6th progress record: lines 18–31 ran twice).
2. A damaged record in the middle (a finished job's log: 12 executed frames re-sent) is not
   taken for the crash's cut: exit 1, nothing sent.
3. An edited record (the line to continue at earlier than the line sent) is refused, not obeyed.
4. Records of the wrong type or shape (target 5, no kind, strings for numbers, a line "x",
   lead_s null, a JSON line 100,000 deep): one line and exit 1 or 2, never a traceback.
5. ``--resume LOG --log LOG`` never truncates the journal being resumed.
6. A log without checksums (format 1) is refused with a clear message.
7. ``--resume LOG`` after a stop on an arm that acts on control frames as they land continues
   or refuses before it sends anything (it sent a connector reset and a pause toggle, then refused).
8. ``armctl decode`` reads the new records.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zlib
from pathlib import Path

import pytest

from armctl import Arm
from armctl.errors import ArmctlError

from journal_crash import VIRTUAL, crash_into, durable_end, job_commands, ran, sent

ROOT = Path(__file__).resolve().parent.parent
JOINT = ROOT / "scripts" / "joint_routine.txt"
PICK = ROOT / "scripts" / "pick_and_place.txt"


def _armctl(*args: str, cwd: Path, timeout: float = 60.0) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    return subprocess.run([sys.executable, "-m", "armctl", *args], capture_output=True, text=True, timeout=timeout,
                          cwd=cwd, env=env)


def _records(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def _written(path: Path) -> list[dict]:
    """The frames a --log records as written (nothing: no file, or no tx record)."""
    return [r for r in _records(path) if r.get("dir") == "tx"] if path.exists() else []


def _reseal(record: dict) -> dict:
    """The record with its checksum made to match again, as an editor who knows the format would
    (a log without checksums is left without)."""
    if "crc" not in record:
        return record
    body = {k: v for k, v in record.items() if k != "crc"}
    body["crc"] = f"{zlib.crc32(json.dumps(body, sort_keys=True, separators=(',', ':')).encode()):08x}"
    return body


def _edit(path: Path, change, out: Path) -> int:
    """``change(record)`` (in place; True when it changed it) on every record; resealed.  The count."""
    lines, changed = [], 0
    for record in _records(path):
        if change(record):
            changed += 1
            record = _reseal(record)
        lines.append(json.dumps(record))
    out.write_text("\n".join(lines) + "\n")
    return changed


def _one_line_refusal(done: subprocess.CompletedProcess, codes=(1,)) -> None:
    assert done.returncode in codes, (done.returncode, done.stdout, done.stderr)
    assert "Traceback" not in done.stderr, done.stderr
    lines = [line for line in done.stderr.splitlines() if line.strip() and not line.startswith("armctl: using the built-in")]
    assert len(lines) == 1, done.stderr


# --- 1. durable before the frame -----------------------------------------------------------------
# On the wall clock the record is fsynced before its frame; on a virtual clock (an arm that lives
# in the host's process, its time moved by the host) it is flushed: nothing runs on after a crash.
WALL = "sim://?speed=10"  # the wall clock, ten times faster: joint_routine in about 1.7 s


def _spy_durability(monkeypatch, arm: Arm, log: Path) -> list:
    """Events: ("fsync", size on disk then) and ("write", frame hex, the log's bytes then)."""
    events: list = []
    real_fsync = os.fsync

    def fsync(descriptor):
        real_fsync(descriptor)
        events.append(("fsync", os.fstat(descriptor).st_size))

    monkeypatch.setattr(os, "fsync", fsync)
    link = arm._link
    real_write = link.write

    def write(frame: bytes) -> None:
        events.append(("write", frame.hex(), log.read_bytes()))
        real_write(frame)

    monkeypatch.setattr(link, "write", write)
    return events


def _check_ahead(events: list, synced: bool) -> int:
    """Each frame written finds its own record last in the log on disk — within what was fsynced
    (``synced``) or flushed; the count of frames checked."""
    size, checked = 0, 0
    for event in events:
        if event[0] == "fsync":
            size = event[1]
            continue
        _, frame, on_disk = event
        durable = on_disk[:size] if synced else on_disk
        assert durable.endswith(b"\n"), "the last record is incomplete when a frame goes out"
        assert json.loads(durable.splitlines()[-1]).get("hex") == frame, "the frame went out before its record"
        checked += 1
    return checked


@pytest.mark.realtime
def test_every_frames_record_is_fsynced_before_the_frame_is_written(tmp_path, monkeypatch):
    log = tmp_path / "job.log"
    with Arm.open(port=WALL) as arm:
        events = _spy_durability(monkeypatch, arm, log)
        with log.open("w", encoding="utf-8") as file:
            arm.run(JOINT, log=file)
    assert _check_ahead(events, synced=True) == len(job_commands(JOINT))


def test_on_a_virtual_clock_every_frames_record_is_written_before_the_frame(tmp_path, monkeypatch):
    log = tmp_path / "job.log"
    with Arm.open(port=VIRTUAL) as arm:
        events = _spy_durability(monkeypatch, arm, log)
        with log.open("w", encoding="utf-8") as file:
            assert arm.run(JOINT, log=file).finished
    assert _check_ahead(events, synced=False) == len(job_commands(JOINT))
    assert not [e for e in events if e[0] == "fsync"]  # flushed, not fsynced: see JournalFile


@pytest.mark.realtime
def test_the_installed_command_fsyncs_each_frames_record_before_the_frame(tmp_path):
    """A fresh process running ``armctl run`` with os.fsync and the port's write watched."""
    log, events = tmp_path / "job.log", tmp_path / "events.txt"
    program = f"""
import os, sys
from armctl.host import link
events = open({str(events)!r}, "w")
real_fsync, real_write = os.fsync, link.Link.write
def fsync(fd):
    real_fsync(fd)
    events.write("fsync %d\\n" % os.fstat(fd).st_size); events.flush()
def write(self, frame):
    events.write("write %s\\n" % frame.hex()); events.flush()
    real_write(self, frame)
os.fsync, link.Link.write = fsync, write
from armctl.ui.cli import main
main(["run", {str(JOINT)!r}, "--port", {WALL!r}, "--no-live", "--log", {str(log)!r}])
"""
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=60, cwd=tmp_path, env=env)
    assert done.returncode in (0, 1), done.stderr  # (on a loaded machine the wall clock may cost a proof)
    data = log.read_bytes()
    synced, writes = 0, 0
    for line in events.read_text().splitlines():
        kind, value = line.split()
        if kind == "fsync":
            synced = int(value)
            continue
        writes += 1
        durable = data[:synced]
        assert durable.endswith(b"\n") and json.loads(durable.splitlines()[-1]).get("hex") == value, (
            f"frame {writes} went out before its record was durable")
    assert writes == len(job_commands(JOINT))


def _power_cut(tmp_path, script: Path, n: int):
    """``script`` on a virtual arm, the host dying after ``n`` frames: the arm runs out its queue.
    The arm (open), the log, and what a power cut leaves of it for sure: everything up to the
    record of the last frame written, which went durable before that frame did."""
    log = tmp_path / "crash.log"
    arm = Arm.open(port=VIRTUAL)
    crash_into(arm, script, n, log)
    data = log.read_bytes()
    return arm, data, durable_end(data)


def test_a_power_cut_leaves_every_written_frames_record_and_the_resume_runs_each_line_once(tmp_path):
    """The issue's case: joint_routine through the API, the host dying after 14 frames.  The log
    a power cut leaves holds the records of all 14 (it held those of 6 before), whatever of the
    tail survives; the resume refuses (nothing sent) or runs lines 33 and 34 once."""
    arm, data, durable = _power_cut(tmp_path, JOINT, 14)
    with arm:
        frames_in_durable = [json.loads(line) for line in data[:durable].splitlines()]
        assert [r.get("n") for r in frames_in_durable if r.get("dir") == "tx"][-1] == 14
        progress = [i for i, line in enumerate(data.splitlines()) if b'"progress"' in line]
        assert durable > len(b"\n".join(data.splitlines()[: progress[5] + 1]))  # past the 6th progress record
        before = ran(arm)
        resumed = []
        for keep in sorted({durable, durable + 40, durable + 400, (durable + len(data)) // 2, len(data)}):
            cut = tmp_path / f"cut-{keep}.log"
            cut.write_bytes(data[:keep])
            received = sent(arm)
            try:
                result = arm.run(JOINT, resume=cut)
            except ArmctlError:
                assert sent(arm) == received, "a refused resume sent frames"
                continue
            resumed.append(keep)
            assert result.finished and ran(arm) == job_commands(JOINT), "a line ran twice or was skipped"
            break  # the job is done on this arm: a second resume would find nothing to do
        assert resumed, "no cut the crash can leave resumed"
        assert before == job_commands(JOINT)[:14]


def test_the_command_resumes_a_power_cut_log_once(tmp_path, monkeypatch):
    """``armctl run --resume`` of the log a power cut left (the host died after 14 frames of
    joint_routine; its arm ran them and rests at home).  The installed command, a fresh process,
    meets a new simulated arm (a ``sim://`` arm dies with its process; it happens to start at
    home too, and was taken for the old one): refused, exit 2 (tests/test_log_port.py).  The
    command on the arm that ran the 14 frames continues at line 33: lines 33 and 34, once."""
    import armctl.host.link
    from click.testing import CliRunner

    from armctl.ui.cli import main

    arm, data, durable = _power_cut(tmp_path, JOINT, 14)
    port = arm._link.port
    arm.close()
    end_of_next_progress = data.index(b"\n", data.index(b'"progress"', durable)) + 1
    cut = tmp_path / "cut.log"
    cut.write_bytes(data[:end_of_next_progress])
    done = _armctl("run", str(JOINT), "--port", VIRTUAL, "--json", "--resume", str(cut), cwd=tmp_path)
    assert done.returncode == 2 and "does not outlive its process" in done.stderr, done.stderr

    def the_same_arm(url, *args, **kwargs):
        port.is_open = True  # reopened: the arm, its FIFO and its virtual clock carry on
        return port

    monkeypatch.setattr(armctl.host.link, "open_port", the_same_arm)
    resumed = CliRunner().invoke(main, ["run", str(JOINT), "--json", "--resume", str(cut)], env={"ARMCTL_PORT": None})
    assert resumed.exit_code == 0, resumed.output
    summary = json.loads(resumed.stdout.splitlines()[-1])
    assert "at line 33" in resumed.stderr and summary["frames_sent"] == 2  # lines 33 and 34, once
    assert ran(port) == job_commands(JOINT)


# --- 2. a damaged record in the middle -----------------------------------------------------------


def _damage_middle(log: Path, out: Path) -> None:
    lines = log.read_bytes().split(b"\n")
    middle = len(lines) // 2
    lines[middle] = lines[middle].replace(b'"t": ', b'"t": 1', 1) if b'"t": ' in lines[middle] else lines[middle][:-3]
    out.write_bytes(b"\n".join(lines))


def test_a_damaged_record_in_the_middle_of_a_finished_log_is_refused_api(tmp_path):
    log, damaged = tmp_path / "job.log", tmp_path / "damaged.log"
    with Arm.open(port=VIRTUAL) as arm:
        with log.open("w", encoding="utf-8") as file:
            assert arm.run(JOINT, log=file).finished
        _damage_middle(log, damaged)
        received = sent(arm)
        with pytest.raises(ArmctlError):
            arm.run(JOINT, resume=damaged)
        assert sent(arm) == received


def test_a_damaged_record_in_the_middle_of_a_finished_log_is_refused_cli(tmp_path):
    log, damaged, again = tmp_path / "job.log", tmp_path / "damaged.log", tmp_path / "again.log"
    assert _armctl("run", str(JOINT), "--port", VIRTUAL, "--no-live", "--log", str(log), cwd=tmp_path).returncode == 0
    _damage_middle(log, damaged)
    done = _armctl("run", str(JOINT), "--port", VIRTUAL, "--no-live", "--resume", str(damaged), "--log", str(again),
                   cwd=tmp_path)
    _one_line_refusal(done)
    assert _written(again) == [], "the resume of a damaged log sent frames"


# --- 3. an edited record ---------------------------------------------------------------------------


def _continue_earlier(record: dict) -> bool:
    """The line to continue at set to line 1, earlier than the line it follows."""
    changed = False
    for key in ("sent_resume", "next"):
        if isinstance(record.get(key), int) and record[key] > 1:
            record[key], changed = 1, True
    return changed


def test_an_edited_record_is_refused_not_obeyed(tmp_path):
    log, edited, again = tmp_path / "job.log", tmp_path / "edited.log", tmp_path / "again.log"
    with Arm.open(port=VIRTUAL) as arm:
        crash_into(arm, PICK, 6, log)
        assert _edit(log, _continue_earlier, edited)
        received = sent(arm)
        with pytest.raises(ArmctlError):
            arm.run(PICK, resume=edited)
        assert sent(arm) == received
    done = _armctl("run", str(PICK), "--port", VIRTUAL, "--no-live", "--resume", str(edited), "--log", str(again),
                   cwd=tmp_path)
    _one_line_refusal(done)
    assert _written(again) == []


# --- 4. records of the wrong type -----------------------------------------------------------------


def _set_target(value):
    def change(record: dict) -> bool:
        if "target" in record:
            record["target"] = value(record["target"])
            return True
        return False
    return change


def _set(key: str, value):
    def change(record: dict) -> bool:
        if key in record:
            record[key] = value
            return True
        return False
    return change


EDITS = {
    "target 5": _set_target(lambda target: 5),
    "target without kind": _set_target(lambda target: {k: v for k, v in (target or {}).items() if k != "kind"}),
    "strings in xyz_mm": _set_target(lambda target: {**(target or {"kind": "line"}), "xyz_mm": ["a", "b", "c"]}),
    "a line 'x'": lambda record: _set("sent_resume", "x")(record) | _set("next", "x")(record),
    "lead_s null": _set("lead_s", None),
}


@pytest.fixture(scope="module")
def stopped_log(tmp_path_factory):
    """pick_and_place journalled through the API, the host dying (virtual clock) after 6 frames."""
    folder = tmp_path_factory.mktemp("stopped")
    log = folder / "job.log"
    with Arm.open(port=VIRTUAL) as arm:
        crash_into(arm, PICK, 6, log)
    return log


@pytest.mark.parametrize("edit", sorted(EDITS))
def test_a_record_of_the_wrong_type_is_one_line_and_exit_1(tmp_path, stopped_log, edit):
    edited = tmp_path / "edited.log"
    assert _edit(stopped_log, EDITS[edit], edited)
    done = _armctl("run", str(PICK), "--port", VIRTUAL, "--no-live", "--resume", str(edited), cwd=tmp_path)
    _one_line_refusal(done, codes=(1, 2))
    with Arm.open(port=VIRTUAL) as arm:
        with pytest.raises(ArmctlError):
            arm.run(PICK, resume=edited)
        assert sent(arm) == 0


@pytest.mark.parametrize("where", ["first", "middle"])
def test_a_json_line_100000_deep_is_one_line_not_a_recursion_error(tmp_path, stopped_log, where):
    deep = "[" * 100_000 + "]" * 100_000
    lines = stopped_log.read_text().splitlines()
    lines.insert(0 if where == "first" else len(lines) // 2, deep)
    edited = tmp_path / "deep.log"
    edited.write_text("\n".join(lines) + "\n")
    done = _armctl("run", str(PICK), "--port", VIRTUAL, "--no-live", "--resume", str(edited), cwd=tmp_path)
    _one_line_refusal(done, codes=(1, 2))
    with Arm.open(port=VIRTUAL) as arm:
        with pytest.raises(ArmctlError):
            arm.run(PICK, resume=edited)


# --- 5. the journal being resumed is never truncated ------------------------------------------------


def test_resume_log_with_log_naming_the_same_file_leaves_it_whole(tmp_path, stopped_log):
    log = tmp_path / "job.log"
    log.write_bytes(stopped_log.read_bytes())
    before = log.read_bytes()
    done = _armctl("run", str(PICK), "--port", VIRTUAL, "--no-live", "--resume", str(log), "--log", str(log), cwd=tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert log.read_bytes() == before
    again = _armctl("run", str(PICK), "--port", VIRTUAL, "--no-live", "--resume", "job.log", "--log", "./job.log",
                    cwd=tmp_path)
    assert again.returncode == 2 and log.read_bytes() == before
    with Arm.open(port=VIRTUAL) as arm, log.open("a", encoding="utf-8") as same:
        with pytest.raises(ArmctlError):
            arm.run(PICK, resume=log, log=same)
        assert sent(arm) == 0
    assert log.read_bytes() == before


# --- 6. logs of an earlier armctl --------------------------------------------------------------------


def test_a_log_without_checksums_is_refused_with_a_clear_message(tmp_path):
    import hashlib

    old = tmp_path / "old.log"
    records = [{"t": 0.0, "dir": "job", "script": str(PICK), "sha256": hashlib.sha256(PICK.read_bytes()).hexdigest(),
                "from_line": 1, "lead_s": 2.0},
               {"t": 0.1, "dir": "tx", "hex": "00" * 48, "line": 12},
               {"t": 0.1, "dir": "progress", "sent_line": 12, "sent_resume": 13, "done_line": None, "done_resume": 12}]
    old.write_text("".join(json.dumps(r) + "\n" for r in records))
    done = _armctl("run", str(PICK), "--port", VIRTUAL, "--no-live", "--resume", str(old), cwd=tmp_path)
    _one_line_refusal(done, codes=(2,))
    assert "checksum" in done.stderr and "--from-line" in done.stderr


# --- 7. --resume after a stop on an arm that acts on control frames as they land --------------------


def test_resume_after_a_stop_on_an_arrival_arm_sends_nothing_before_it_decides(tmp_path):
    profile = tmp_path / "arm.toml"
    profile.write_text('[connector]\ncontrol_frames = "arrival"\n')
    log = tmp_path / "job.log"
    with Arm.open(port=VIRTUAL + "&control_frames=arrival", profile=profile) as arm:
        def stop(progress):
            if progress.frames_sent >= 8:
                arm.stop()

        with log.open("w", encoding="utf-8") as file:
            first = arm.run(PICK, on_progress=stop, log=file)
        assert first.outcome == "interrupted"
        received = sent(arm)
        try:
            rest = arm.run(PICK, resume=log)
        except ArmctlError as error:
            assert "nothing was sent" in str(error)
            assert sent(arm) == received, "the resume sent frames (a reset, a pause toggle), then refused"
        else:
            assert rest.finished and ran(arm) == job_commands(PICK)


# --- 8. decode ----------------------------------------------------------------------------------------


def test_decode_reads_the_journal(tmp_path):
    log = tmp_path / "job.log"
    assert _armctl("run", str(JOINT), "--port", VIRTUAL, "--no-live", "--log", str(log), cwd=tmp_path).returncode == 0
    done = _armctl("decode", str(log), "--json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    frames = [json.loads(line) for line in done.stdout.splitlines()]
    motion = [f["hex"] for f in frames if f.get("family") == "motion"]
    assert motion == [command.encode().hex() for command in job_commands(JOINT)]  # every frame written, in order
    assert sum(1 for f in frames if f.get("family") == "status") > 100


@pytest.mark.realtime
def test_the_installed_command_resumes_after_ctrl_c_on_an_arrival_arm_or_refuses_sending_nothing(tmp_path):
    """Issue 21: ``--resume LOG`` after a Ctrl-C on the same arm (``armctl sim --pty``, control
    frames acting as they land) sent a connector reset and a pause toggle, then refused."""
    import re
    import signal
    import time

    (tmp_path / "armctl.toml").write_text('[connector]\ncontrol_frames = "arrival"\nfifo_frames = 200\n')
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    sim = subprocess.Popen([sys.executable, "-m", "armctl", "sim", "--pty", "--url", "sim://?control_frames=arrival"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path)
    try:
        pty = re.search(r"(/dev/\S+)", sim.stdout.readline()).group(1)
        log, again = tmp_path / "job.log", tmp_path / "again.log"
        host = subprocess.Popen([sys.executable, "-m", "armctl", "run", str(PICK), "--port", pty, "--no-live",
                                 "--log", str(log)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                cwd=tmp_path, env=env)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and sum(1 for r in _written(log) if r.get("line") is not None) < 3:
            time.sleep(0.1)
        host.send_signal(signal.SIGINT)
        host.communicate(timeout=60)
        assert host.returncode == 130
        done = _armctl("run", str(PICK), "--port", pty, "--no-live", "--resume", str(log), "--log", str(again),
                       cwd=tmp_path, timeout=120)
        if done.returncode != 0:
            _one_line_refusal(done)
            assert "sending a reset" not in done.stderr and "pause toggle to resume" not in done.stderr, done.stderr
            assert _written(again) == []
        else:
            assert "finished: the arm finished the job" in done.stdout
    finally:
        sim.terminate()
        sim.wait(10)
