"""A day's log resumes: ``--resume`` read a log whole, and refused one over 128 MiB (the bound of
every input) — at about 7 KB/s of journal, any job longer than about 5.4 hours, while a job may
run 24 hours (found by the crash review: a 7 h virtual job wrote 174,487,905 bytes and its
resume said "longer than 128 MiB … (is this the file you meant?)", exit 2).  Now a resume log
is read line by line up to ``MAX_LOG_BYTES`` (2 GiB), each line at most ``MAX_LINE_BYTES``, and
the frames it records are kept compact (``joblog.Frames``: a frame's target only while it may
still decide the resume).  The figures for a 316 MB log are ``benchmarks/resume_memory.py``'s.
"""

from __future__ import annotations

import pytest

import armctl.host.inputs as inputs
from armctl.core.joblog import job_record, seal, target_of
from armctl.errors import UnusableInput
from armctl.host.jobflow import read_resume_point
from armctl.script.files import ScriptSnapshot

pytestmark = pytest.mark.timeout(60)


def _log(path, frames: int, tail: bytes = b"") -> ScriptSnapshot:
    """A log of ``frames`` frames (two status records after each) of a script of as many lines."""
    data = "".join(f"G1 X{200 + k % 50} Y0 Z250 A180 B0 C0 S1500 F3000\n" for k in range(frames)).encode()
    records = [job_record("job.txt", data, 1, 2.0, frames)]
    for k in range(1, frames + 1):
        records.append({"t": k * 0.05, "dir": "tx", "hex": "ee" * 48, "line": k, "n": k, "at": k,
                        "next": k + 1 if k < frames else None,
                        "target": target_of("line", (200.0 + (k - 1) % 50, 0.0, 250.0), (0.0,) * 6)})
        records += [{"t": k * 0.05, "dir": "rx", "hex": "a5" + "00" * 7 + "5a"}] * 2
    path.write_bytes("".join(seal(r, seq) + "\n" for seq, r in enumerate(records)).encode() + tail)
    return ScriptSnapshot("job.txt", data)


def test_a_log_is_bounded_by_the_log_limit_not_the_input_limit():
    # a day's journal at ~7 KB/s (0.6 GB) fits; the bound of a script or a decode input does not
    assert inputs.MAX_LOG_BYTES >= 24 * 3600 * 7_000 > inputs.MAX_INPUT_BYTES


def test_a_log_over_the_log_limit_is_refused_before_it_is_read(tmp_path, monkeypatch):
    script = _log(tmp_path / "j.log", 40)
    monkeypatch.setattr(inputs, "MAX_LOG_BYTES", 4096)
    with pytest.raises(UnusableInput, match="longer than 4 KiB"):
        read_resume_point(str(tmp_path / "j.log"), script)


def test_only_the_targets_that_may_decide_the_resume_are_kept(tmp_path):
    script = _log(tmp_path / "j.log", 3000)
    point = read_resume_point(str(tmp_path / "j.log"), script)
    assert len(point.frames) == 3000 and point.confirmed == 2999
    assert sorted(point.frames.targets) == [2998, 2999]  # the candidates' (frames_run): the last two
    assert point.frames[-1].target is not None and point.frames[0].target is None
    assert point.line_for((249.0, 0.0, 250.0), (0.0,) * 6) is None  # at the last frame's target: every line ran
    assert point.line_for((248.0, 0.0, 250.0), (0.0,) * 6) == 3000  # at the one before: the last line is left


@pytest.mark.parametrize("tail, readable", [(b"\0" * (inputs.MAX_LINE_BYTES + 10), True),
                                            (b"x" * (inputs.MAX_LINE_BYTES + 10), False)],
                         ids=["NUL blocks after the last record", "a line no journal writes"])
def test_a_long_last_line(tail, readable, tmp_path):
    # unwritten blocks after the crash read as the torn end they are; a line over 1 MiB of anything
    # else is no journal's, and is refused rather than held in memory
    script = _log(tmp_path / "j.log", 20, tail)
    if readable:
        assert read_resume_point(str(tmp_path / "j.log"), script).line_for((219.0, 0.0, 250.0), (0.0,) * 6) is None
    else:
        with pytest.raises(UnusableInput, match="a line longer than 1 MiB"):
            read_resume_point(str(tmp_path / "j.log"), script)
