"""The job records of ``run --log`` and what ``run --resume LOG`` reads back from them.

Strategy: the log already holds every frame written and read (``tx``/``rx`` records, which
``armctl decode`` reads).  Two more kinds of record make it a journal a new process can resume
from after the host died (kill -9, a power cut) — pure data in, pure data out, no I/O here:

- ``job``, first: which script (its name and the SHA-256 of the snapshot that was checked and
  sent), from which line, with which lead.  ``--resume`` with another script, or the same
  file edited since, refuses (``ResumeRefused``, exit 2): the lines would not mean the same.
- ``progress``, each time what is known changes: the last line sent and the last line known
  executed, with the line to resume at in each case (``--from-line`` rules: never inside an
  arc, a repeat block from its outermost start) and the target of the last frame written.

After a crash the arm keeps running what was queued (at most the lead), so the last line
*known* executed at the crash is an underestimate.  ``ResumePoint.line_for`` decides from the
arm's own report at resume time, which is the proof: at rest at the last written target ⇒
every frame written ran (continue after the last line sent); nothing in flight ⇒ continue after
the last line known executed; anything else cannot be proven and is refused (exit 1) rather
than run a line twice or skip one.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from typing import Iterable

from .errors import ArmctlError, ResumeRefused
from .protocol import ArcEnd
from .job import TARGET_DEG, TARGET_MM  # "at the target" as the end of a job judges it



def script_digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def job_record(name: str, data: bytes, from_line: int, lead_s: float) -> dict:
    return {"t": 0.0, "dir": "job", "script": name, "sha256": script_digest(data), "from_line": from_line, "lead_s": lead_s}


def progress_record(t_s: float, sent_line, sent_resume, target, done_line, done_resume) -> dict:
    """``target``: (kind, xyz_mm, joints_deg) of the last frame written, or None."""
    record = {"t": round(t_s, 4), "dir": "progress", "sent_line": sent_line, "sent_resume": sent_resume,
              "done_line": done_line, "done_resume": done_resume}
    if target is not None:
        kind, xyz, joints = target
        record["target"] = {"kind": kind, "xyz_mm": [round(v, 4) for v in xyz], "joints_deg": [round(v, 4) for v in joints]}
    return record


@dataclass(frozen=True)
class ResumePoint:
    """What the log proves about the job it records."""

    from_line: int  # where the logged run started
    lead_s: float
    sent_line: int | None = None
    sent_resume: int | None = None  # where to continue if every frame written ran (None: the job was all sent)
    done_line: int | None = None
    done_resume: int | None = None
    target: dict | None = None
    # Job frames (``tx`` records with a line) the log shows written after its last ``progress``
    # record: the host died between a write and its journal entry, so what they were is unknown.
    unjournaled_frames: int = 0

    def line_for(self, position_mm, joints_deg) -> int | None:
        """The line to continue at, given where the arm reports it is at rest now; None when
        every line already ran; ``NotProven`` when the report proves neither."""
        if self.unjournaled_frames:
            raise NotProven(self)  # neither the line to go on from nor the target to check is known
        if self.sent_line is None:
            return self.from_line  # nothing was written
        if self.at_target(position_mm, joints_deg):
            return self.sent_resume  # the queue ran out after the host died: everything written ran
        if self.done_line == self.sent_line:
            return self.done_resume
        raise NotProven(self)

    def at_target(self, position_mm, joints_deg) -> bool:
        target = self.target
        if target is None:
            return False
        if target["kind"] == "joint":
            return None not in joints_deg and max(abs(a - b) for a, b in zip(joints_deg, target["joints_deg"])) <= TARGET_DEG
        return position_mm is not None and max(abs(a - b) for a, b in zip(position_mm, target["xyz_mm"])) <= TARGET_MM


class NotProven(ArmctlError):
    """The arm is neither at the last target written nor was the log's last frame known done."""

    def __init__(self, point: ResumePoint) -> None:
        self.point = point
        done = point.done_line if point.done_line is not None else "none"
        if point.unjournaled_frames:
            super().__init__(
                f"the log shows {point.unjournaled_frames} frame(s) written after its last progress record (the host "
                f"stopped between the write and its record): armctl cannot prove which lines ran; nothing was sent "
                f"(check the arm and continue by hand with --from-line)")
            return
        super().__init__(
            f"the log's last line sent is {point.sent_line} and the last line known executed {done}, but the arm is not "
            f"at rest at the last target written: armctl cannot prove which lines in between ran; nothing was sent "
            f"(check the arm and continue by hand with --from-line)")


def read_resume_log(lines: Iterable[str], name: str, data: bytes) -> ResumePoint:
    """The resume point recorded in a ``--log`` for the script ``name`` whose snapshot is ``data``."""
    header, last, unjournaled = None, None, 0
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except ValueError:
            if header is None:
                raise ResumeRefused(f"line {number} is not JSON: not a `run --log` file") from None
            break  # a line cut by the crash: what came before is complete
        if not isinstance(record, dict):
            continue
        if record.get("dir") == "job" and header is None:
            header = record
        elif record.get("dir") == "progress":
            last, unjournaled = record, 0
        elif record.get("dir") == "tx" and record.get("line") is not None:
            unjournaled += 1  # a job frame; its progress record follows it (Journal.update) unless the host died
    if header is None:
        raise ResumeRefused("it has no job record (written by `armctl run --log` since --resume exists)")
    if header.get("sha256") != script_digest(data):
        logged = header.get("script")
        same = "the same name" if logged == name else f"{logged!r}"
        raise ResumeRefused(f"it records {same} with other contents (sha256 {str(header.get('sha256'))[:12]}…, "
                            f"{name} is {script_digest(data)[:12]}…): the script was edited or is another one")
    if last is None:
        return ResumePoint(header.get("from_line", 1), header.get("lead_s", 0.0), unjournaled_frames=unjournaled)
    return ResumePoint(header.get("from_line", 1), header.get("lead_s", 0.0), last.get("sent_line"), last.get("sent_resume"),
                       last.get("done_line"), last.get("done_resume"), last.get("target"), unjournaled)


class Journal:
    """Writes a ``progress`` record through ``write`` (a dict → the log) whenever the last line
    sent or the last line known executed changes; ``resume_at(statement)`` is the line
    ``--from-line`` would take to continue at ``statement`` (arcs, repeat blocks)."""

    def __init__(self, write, resume_at) -> None:
        self.write, self.resume_at = write, resume_at
        self._told = None
        self._target = None

    def update(self, view, last_segment) -> None:
        """``last_segment``: the planned segment of the last frame written (its end is the target)."""
        sent, done = view.last_sent, view.last_done
        told = (view.frames_sent, None if done is None else done.line, view.first_not_done is None)
        if told == self._told:
            return
        if self._told is None or view.frames_sent != self._told[0]:
            if last_segment is not None:
                self._target = (last_segment.kind, last_segment.end.xyz, last_segment.end.joints)
        self._told = told
        next_statement = view.next_statement
        if next_statement is not None and sent is not None and isinstance(next_statement.command, ArcEnd):
            next_statement = sent  # a G301 cannot start a job: continue at its G300
        self.write(progress_record(
            view.now_s - view.started_s, None if sent is None else sent.line,
            None if next_statement is None else self.resume_at(next_statement), self._target,
            None if done is None else done.line,
            None if view.first_not_done is None else self.resume_at(view.first_not_done)))
