"""armctl/core/joblog.py's records and reader, pure: sealing, the intact prefix, the consistency
checks, and the proof from the arm's report (the candidates a crash leaves uncertain).

Strategy: one real journal (scripts/joint_routine.txt through the API on a virtual clock, the
host dying after 14 frames — the issue's case) read back with one thing changed at a time.
"""

from __future__ import annotations

import io

import json
import zlib
from pathlib import Path

import pytest

from armctl.errors import ResumeRefused
from armctl.core.joblog import JournalDamaged, NotProven, read_resume_lines, seal, unseal
from armctl.script.files import read_script

from journal_crash import make_crash

JOINT = Path(__file__).resolve().parent.parent / "scripts" / "joint_routine.txt"


@pytest.fixture(scope="module")
def crash(tmp_path_factory):
    return make_crash(JOINT, 14, tmp_path_factory.mktemp("crash") / "job.log")


def _read(text: str):
    snapshot = read_script(str(JOINT))
    return read_resume_lines(io.StringIO(text), snapshot.name, snapshot.data)


def _lines(crash) -> list[str]:
    return crash.log.decode().splitlines()


def _resealed(line: str, **changes) -> str:
    record = json.loads(line)
    record.pop("crc")
    record.update(changes)
    record["crc"] = f"{zlib.crc32(json.dumps(record, sort_keys=True, separators=(',', ':')).encode()):08x}"
    return json.dumps(record)


def test_a_record_is_sealed_and_any_change_breaks_the_seal():
    line = seal({"dir": "rx", "hex": "ce0000000000000000cf", "t": 1.5}, 7)
    assert unseal(line) == {"dir": "rx", "hex": "ce0000000000000000cf", "t": 1.5, "seq": 7}
    assert unseal(line.replace("1.5", "1.6")) is None
    assert unseal(line.replace('"seq": 7', '"seq": 8')) is None
    assert unseal("[" * 100_000) is None  # too deep for the parser: damaged, not a RecursionError


def test_the_intact_log_resumes_after_the_last_frame(crash):
    point = _read(crash.log.decode())
    assert point.line_for(*crash.rest) == 33 and crash.correct(33)


def test_a_torn_last_line_is_the_crashs_cut_and_said(crash):
    text = crash.log.decode()
    torn = text[: crash.durable_end] + text[crash.durable_end: crash.durable_end + 30]  # mid-record, no line break
    point = _read(torn)
    assert point.notes and "torn" in point.notes[0]
    assert len(point.frames) == 14


def test_a_damaged_complete_last_line_is_not_a_cut(crash):
    lines = _lines(crash)
    lines[-1] = lines[-1].replace('"t": ', '"t": 9', 1)
    with pytest.raises(JournalDamaged, match=f"line {len(lines)}"):
        _read("\n".join(lines) + "\n")


def test_a_record_dropped_or_repeated_in_the_middle_is_out_of_place(crash):
    lines = _lines(crash)
    for changed in (lines[:40] + lines[41:], lines[:40] + [lines[40]] + lines[40:]):
        with pytest.raises(JournalDamaged, match="out of its place"):
            _read("\n".join(changed) + "\n")


def test_a_frame_that_does_not_follow_the_one_before_is_refused_even_resealed(crash):
    lines = _lines(crash)
    index = next(i for i, line in enumerate(lines) if '"n": 5,' in line)
    lines[index] = _resealed(lines[index], at=10)  # where the frame before said 19
    with pytest.raises(JournalDamaged, match="starts at line 10 where the frame before it said"):
        _read("\n".join(lines) + "\n")


def test_a_progress_record_cannot_claim_a_frame_the_log_has_no_record_of(crash):
    lines = _lines(crash)
    index = next(i for i, line in enumerate(lines) if '"progress"' in line)
    lines[index] = _resealed(lines[index], frames_sent=9)
    with pytest.raises(JournalDamaged, match="counts 9 frames written"):
        _read("\n".join(lines) + "\n")


def test_a_frame_whose_write_is_unconfirmed_at_a_repeated_target_is_not_guessed(crash):
    """The log up to frame 14's record, nothing after: frame 14 (line 31, home, S1000) may or may
    not have gone out, and frame 13 (line 30, home, S2000) leaves the arm at the same place:
    which of them ran last cannot be proven by position."""
    point = _read(crash.log.decode()[: crash.durable_end])
    assert (point.confirmed, len(point.frames)) == (13, 14)
    with pytest.raises(NotProven, match="30, 31 all leave it"):
        point.line_for(*crash.rest)


def test_another_or_an_edited_script_is_refused(crash):
    with pytest.raises(ResumeRefused, match="other contents"):
        read_resume_lines(io.StringIO(crash.log.decode()), str(JOINT), JOINT.read_bytes() + b"G4 P1\n")


def test_runs_appended_to_one_log_resume_the_last(crash, tmp_path):
    """A log file opened for appending holds one run after another: the last job record starts
    the job a resume continues, each run's records counted from 0."""
    other = make_crash(JOINT.parent / "pick_and_place.txt", 3, tmp_path / "other.log")
    point = _read(other.log.decode() + crash.log.decode())
    assert point.line_for(*crash.rest) == 33
    with pytest.raises(ResumeRefused, match="other contents"):
        _read(crash.log.decode() + other.log.decode())
