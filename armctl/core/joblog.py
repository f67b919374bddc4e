"""The journal of ``run --log`` — a write-ahead log — and what ``run --resume LOG`` proves from it.

Strategy: SQLite's WAL is the model.  The log holds every frame written and read (``tx``/``rx``
records, which ``armctl decode`` reads); the runner makes a job frame's record durable (flushed
and fsynced) *before* the frame goes to the port, so a crash (kill -9, a power cut) can lose
only records of frames that were never written and what the host learnt after them.  Every
record is sealed (``seal``): its place in the file (``seq``) and a CRC-32 of its canonical JSON
(``crc``), so a torn, corrupted, edited, dropped or moved record is detected.  Pure data in,
pure data out, no I/O here:

- ``job``, first: which script (its name and the SHA-256 of the snapshot that was checked and
  sent), from which line, with which lead, how many frames, whether control frames act on
  arrival, where the arm stood (``start``) and the port it is on (``port``; absent in a log
  written before armctl recorded it: the port is then unknown) — for a ``sim://`` port, the
  process its simulated arm lives and dies in (``sim_process``: a resume in another process
  meets a new arm, and is refused), and the identity of the arm on the port (``arm``:
  ``calibration.arm_identity``, a USB adapter's serial number; absent in an older log: unknown;
  a resume on another arm is refused).  Another script, or the same
  file edited since, is refused (``ResumeRefused``, exit 2): the lines would not mean the same.
- a job frame's ``tx`` record (``frame_record``), before the frame is written: its number
  ``n`` in the job, its ``line``, ``at`` (where to continue if it did not run: ``--from-line``
  rules, never inside an arc, a repeat block from its outermost start), ``next`` (where to
  continue if it ran; null: it is the job's last frame) and ``target`` (where it leaves the arm).
- ``progress``, each time what is known changes: frames written (``frames_sent``: a write that
  returned) and frames the arm's reports prove done (``done_n``), with the lines for people.
- ``resumed`` (``resumed_record``), appended by a ``--resume`` of this log, durable before that
  resume's first frame goes: where it continued and the log it wrote.  A log is resumed once:
  the arm can stand where the log's last frame leaves it again later (jogged back, a job that
  returns there), and a second resume would run again every line the first one ran; it is
  refused (exit 2), naming the log to resume instead.

``read_resume_lines`` trusts only the longest intact prefix: a damaged last line without its
line break is the tear a crash leaves (a record made durable before its frame always ends with
one); any other damaged record — a complete line, one followed by intact records, or a whole
record followed by bytes other than its line break (a flipped bit there: its frame was written) —
is not a crash cut and the resume is refused (``JournalDamaged``, exit 1).  Records are checked for type
and consistency before use (each frame's ``next`` is the following frame's ``at``; no progress
claims a frame the log has no record of).  Logs without checksums (written before format 2)
are refused: nothing in them tells a cut from a corrupted record.

``ResumePoint.line_for`` decides from the arm's own report at rest, which is the proof.  After
a crash the arm runs out what was queued, so every frame written ran — unless control frames
that clear or freeze the queue were written (a reset, or any control frame on an arm that acts
on them as they land): then only what the reports proved done counts.  The frames written are
the ones the log proves written, plus possibly the last ones whose record is durable but
whose write the log does not confirm; the last frame that ran is the one among those
candidates whose target the arm rests at — exactly one, or the resume is refused (exit 1,
nothing sent): a job that comes back to an earlier target cannot be told apart by position.
"""

from __future__ import annotations

import hashlib
import json
import math
import zlib
from array import array
from dataclasses import dataclass, field
from typing import Any, Iterable

from ..errors import ArmctlError, ResumeRefused
from .protocol import ArcEnd
from .job import TARGET_DEG, TARGET_MM  # "at the target" as the end of a job judges it

FORMAT = 2  # 1: no checksums (before the write-ahead journal); 2: sealed records


def script_digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _canonical(record: dict) -> bytes:
    return json.dumps(record, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode("ascii")


def _crc(record: dict) -> str:
    return f"{zlib.crc32(_canonical(record)):08x}"


def seal(record: dict, seq: int) -> str:
    """``record`` as one journal line (no line break): its place ``seq`` and its CRC-32 added."""
    sealed = {**record, "seq": seq}
    sealed["crc"] = _crc(sealed)
    return json.dumps(sealed)


def unseal(line: str) -> dict | None:
    """The record on ``line`` if it is intact (JSON object, its CRC matches), else None."""
    try:
        record = json.loads(line)
    except (ValueError, RecursionError):  # not JSON, or nested too deep for the parser
        return None
    return record if isinstance(record, dict) and intact(record) else None  # (``intact`` checks the crc is one)


def damage_of(line: str) -> str:
    """Why ``line`` holds no intact record (``unseal`` gave None), for the message naming it."""
    try:
        record = json.loads(line)
    except RecursionError:
        return "nested too deep to read"
    except ValueError:
        return "not JSON"
    return "its checksum does not match" if isinstance(record, dict) and "crc" in record else "not a sealed record"


def torn(line: str, complete: bool) -> bool:
    """A ``line`` that holds no intact record is the crash's cut when it is the log's last and has
    no line break (a record made durable before its frame always ends with one) — and is no whole
    record with other bytes where its line break belongs (``_sealed_then_more``).  Any other damaged
    line ends what the log proves: only its intact prefix is trusted (``--resume``, ``armctl decode``)."""
    return not complete and not _sealed_then_more(line)


def in_place(seq, expected: int) -> bool:
    """A sealed record's ``seq`` where the log puts it: the one due (``expected``), or 0 (a run
    appended to the log); else a record was dropped, moved or added."""
    return _is_int(seq) and seq in (0, expected)


def intact(record: dict) -> bool:
    """A parsed sealed record's CRC-32 matches the rest of it (its ``crc`` is taken out)."""
    crc = record.pop("crc", None)
    try:
        return isinstance(crc, str) and _crc(record) == crc
    except (ValueError, RecursionError, TypeError):
        return False


def resumed_record(at_line: int, into: str | None) -> dict:
    """The record a resume appends to the log it continues, durable before its first frame goes:
    it continued at ``at_line``, journalled to ``into`` (None: no --log).  The log is resumed once."""
    return {"t": 0.0, "dir": "resumed", "at": at_line, "into": into}


def target_of(segment_end_kind: str, xyz, joints) -> dict:
    return {"kind": segment_end_kind, "xyz_mm": [round(v, 4) for v in xyz], "joints_deg": [round(v, 4) for v in joints]}


def job_record(name: str, data: bytes, from_line: int, lead_s: float, frames: int = 0,
               control_on_arrival: bool = False, start: dict | None = None, port: str | None = None,
               sim_process: str | None = None, arm: str | None = None) -> dict:
    return {"t": 0.0, "dir": "job", "format": FORMAT, "script": name, "sha256": script_digest(data),
            "from_line": from_line, "lead_s": lead_s, "frames": frames, "control_on_arrival": control_on_arrival,
            "start": start, "port": port, "sim_process": sim_process, "arm": arm}


def frame_record(n: int, line: int, at: int, next_line: int | None, target: dict | None) -> dict:
    """The journal's fields of job frame ``n`` (the runner adds ``t``, ``dir``, ``hex``)."""
    return {"n": n, "line": line, "at": at, "next": next_line, "target": target}


def progress_record(t_s: float, frames_sent: int, done_n: int, sent_line, done_line, done_resume) -> dict:
    return {"t": round(t_s, 4), "dir": "progress", "frames_sent": frames_sent, "done_n": done_n,
            "sent_line": sent_line, "done_line": done_line, "done_resume": done_resume}


class JournalDamaged(ArmctlError):
    """The log is readable but not intact or not consistent: it cannot prove the resume line (exit 1)."""


class NotProven(ArmctlError):
    """The log and the arm's report at rest do not prove which line to continue at (exit 1)."""


class PlainWords:
    """How a refusal names a resume and the line to start at when no interface passed its words:
    each interface has its ``ResumeWords`` (armctl/host/resume_words.py), handed down to the reader
    and kept with the ``ResumePoint``; the core names no interface's flags."""

    bare = "a resume"
    from_line = "a line you choose"

    @staticmethod
    def naming(log) -> str:
        return str(log)


def _by_hand(words) -> str:
    """The way out of a resume the log cannot prove: the user decides the line."""
    return f"check the arm and continue by hand with {words.from_line}"


@dataclass(frozen=True)
class FrameEntry:
    n: int
    line: int
    at: int
    next: int | None
    target: dict | None


class Frames:
    """The job frames a log records, compact enough for a 24-hour job's (up to the 2,000,000-line
    limit): each frame's line, ``at`` and ``next`` in arrays (a ``next`` of None as 0: lines count
    from 1), its target kept only while it may still decide the resume (``forget_targets_before``:
    the candidates are the frames the log does not prove written, ``ResumePoint.frames_run``).
    A sequence of ``FrameEntry`` as a tuple of them is (an int index; a forgotten target reads None)."""

    def __init__(self, entries=()) -> None:
        self.lines, self.ats, self.nexts = array("q"), array("q"), array("q")
        self.targets: dict[int, dict | None] = {}  # index → target, for the frames not forgotten
        for entry in entries:
            self.append(entry.line, entry.at, entry.next, entry.target)

    def append(self, line: int, at: int, after: int | None, target: dict | None) -> None:
        self.targets[len(self.lines)] = target
        self.lines.append(line)
        self.ats.append(at)
        self.nexts.append(0 if after is None else after)

    def forget_targets_before(self, index: int) -> None:
        """Targets of the frames before ``index`` are not needed any more (the log proves them written)."""
        for old in [k for k in self.targets if k < index]:
            del self.targets[old]

    def __len__(self) -> int:
        return len(self.lines)

    def __getitem__(self, index: int) -> FrameEntry:
        index = range(len(self.lines))[index]  # (negative indexes; IndexError past the end)
        after = self.nexts[index]
        return FrameEntry(index + 1, self.lines[index], self.ats[index], after or None, self.targets.get(index))


@dataclass(frozen=True)
class ResumePoint:
    """What the intact prefix of a log proves about the job it records."""

    from_line: int  # where the logged run started
    lead_s: float
    frames: Any = ()  # every job frame whose record is durable, in order: a Frames (or FrameEntry tuple)
    confirmed: int = 0  # frames the log proves written (a later record, or a progress record)
    done: int = 0  # frames the arm's reports proved done
    start: dict | None = None  # where the arm stood when the job began
    cleared: str | None = None  # why "every frame written ran" does not hold (None: it does)
    notes: tuple = field(default_factory=tuple)
    log_path: str | None = None  # the log it was read from: the resume marks it (``resumed_record``)
    port: str | None = None  # the port the job ran on (None: a log written before armctl recorded it)
    sim_process: str | None = None  # a sim:// port's: the process its simulated arm lived (and died) in
    arm: str | None = None  # the identity of the arm on ``port`` when the job began (None: unknown, an older log)
    # how the interface that read it names a resume and a line in its refusals (``PlainWords`` by default)
    words: Any = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.frames, Frames):
            object.__setattr__(self, "frames", Frames(self.frames))

    @property
    def sent_line(self) -> int | None:
        return self.frames[-1].line if self.frames else None

    def line_for(self, position_mm, joints_deg) -> int | None:
        """The line to continue at, given where the arm reports it rests now; None when every
        line already ran; ``NotProven`` when the report and the log prove no single line."""
        return self.after(self.frames_run(position_mm, joints_deg))

    def frames_run(self, position_mm, joints_deg) -> int:
        """How many of the log's frames ran, given where the arm reports it rests now;
        ``NotProven`` when the report and the log prove no single count."""
        written, words = len(self.frames), self.words or PlainWords
        if written == 0:
            return 0  # nothing was written: a frame is written only after its record
        if self.done == written:
            return written  # the arm's reports proved every frame written done (wherever it stands now: ``moved_from``)
        if self.cleared is not None:
            raise NotProven(f"{self.cleared}, so the frames after the last one the arm's reports proved done "
                            f"({self.done} of {written} written) may or may not have run: armctl cannot prove "
                            f"which lines ran; nothing was sent ({_by_hand(words)})")
        first = max(self.confirmed, self.done)
        candidates = [e for e in range(first, written + 1) if _at(self._target(e), position_mm, joints_deg)]
        if len(candidates) == 1:
            return candidates[0]
        lines = ", ".join(str(self.frames[e - 1].line) if e else "the start" for e in range(first, written + 1))
        if not candidates:
            raise NotProven(f"the arm is not at rest where the log's last frame{'s' if written > first else ''} "
                            f"({lines}) leave{'' if written > first else 's'} it: armctl cannot prove which lines ran; "
                            f"nothing was sent ({_by_hand(words)})")
        ends = ", ".join(str(self.frames[e - 1].line) if e else "the start" for e in candidates)
        raise NotProven(f"the arm rests where {ends} all leave it and the log cannot prove which of them ran last: "
                        f"armctl cannot prove the line to continue at; nothing was sent ({_by_hand(words)})")

    def moved_from(self, position_mm, joints_deg) -> int | None:
        """The line of the log's last frame when the arm's reports proved every frame written done
        but the arm is not at rest at that frame's target (moved since: a jog, a move, another job);
        else None.  The resume still continues after it — no line runs twice — but the next
        move starts from where the arm is, which the person resuming must be told."""
        written = len(self.frames)
        if written == 0 or self.done != written:
            return None
        target = self._target(written)
        return None if target is None or _at(target, position_mm, joints_deg) else self.frames[written - 1].line

    def after(self, ran: int) -> int | None:
        """The line to continue at once the first ``ran`` frames ran (None: every line did)."""
        if ran == 0:
            return self.frames[0].at if self.frames else self.from_line
        return self.frames[ran - 1].next

    def repeated(self, ran: int) -> int | None:
        """The last line, among the first ``ran`` frames, at or past the line to continue at: the
        resume starts again the repeat block the job stopped in (no job starts inside one, as
        ``--from-line``), so its passes already done run again up to that line.  None: no line
        runs twice."""
        line = self.after(ran)
        if line is None:
            return None
        return max((ran_line for ran_line in self.frames.lines[:ran] if ran_line >= line), default=None)

    def _target(self, e: int) -> dict | None:
        return self.start if e == 0 else self.frames[e - 1].target



def _at(target, position_mm, joints_deg) -> bool:
    """The arm at rest at ``target`` (a checked target dict; None: unknown, never)."""
    if target is None:
        return False
    if target["kind"] == "joint":
        return (None not in joints_deg and len(joints_deg) == 6
                and max(abs(a - b) for a, b in zip(joints_deg, target["joints_deg"])) <= TARGET_DEG)
    return position_mm is not None and max(abs(a - b) for a, b in zip(position_mm, target["xyz_mm"])) <= TARGET_MM


# --- reading ---------------------------------------------------------------------------------


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _numbers(value, count: int) -> bool:
    return isinstance(value, list) and len(value) == count and all(_is_number(v) for v in value)


def _valid_target(value) -> bool:
    return (isinstance(value, dict) and isinstance(value.get("kind"), str) and _numbers(value.get("xyz_mm"), 3)
            and _numbers(value.get("joints_deg"), 6))


def _is_hex_frame(value) -> bool:
    if not isinstance(value, str) or len(value) > 1024:
        return False
    try:
        bytes.fromhex(value)
    except ValueError:
        return False
    return True


class _Reader:
    """One pass over the sealed records of a log; ``point`` once all were read."""

    def __init__(self, name: str, data: bytes, log: str | None = None, words=None) -> None:
        self.name, self.data = name, data
        self.log = log  # the log's name, for messages (file:line); None: "line N"
        self.words = words or PlainWords  # how the interface reading it names a resume and a line
        self.header: dict | None = None
        self.frames = Frames()
        self.confirmed = self.done = 0
        self.cleared: str | None = None
        self.resumed: dict | None = None  # the resume that continued this job already (``resumed_record``)

    def bad(self, number: int, why: str):
        where = f"line {number}" if self.log is None else f"{self.log}:{number}"
        return JournalDamaged(f"{where}: {why}: the log cannot prove which lines ran; nothing was sent")

    def take(self, number: int, record: dict) -> None:
        kind = record.get("dir")
        if kind == "job":
            self.job(number, record)
        elif self.header is None:
            return  # before the job record: the arm's reading (a pause resumed), nothing of the job
        elif kind == "tx":
            self.tx(number, record)
        elif kind == "progress":
            self.progress(number, record)
        elif kind == "resumed":
            at, into = record.get("at"), record.get("into")
            if not (_is_int(at) and at >= 1 and (into is None or isinstance(into, str))):
                raise self.bad(number, "a resumed record's fields are not what armctl writes")
            self.resumed = record
        elif kind == "rx":
            if not _is_hex_frame(record.get("hex")):
                raise self.bad(number, "a status record without its frame")

    def job(self, number: int, record: dict) -> None:
        if record.get("format") != FORMAT:
            raise ResumeRefused(f"line {number}: a job record of format {record.get('format')!r}; this armctl reads "
                                f"format {FORMAT}")
        from_line, lead_s, frames = record.get("from_line"), record.get("lead_s"), record.get("frames")
        start, arrival, port = record.get("start"), record.get("control_on_arrival"), record.get("port")
        if not (_is_int(from_line) and from_line >= 1 and _is_number(lead_s) and lead_s >= 0 and _is_int(frames)
                and frames >= 0 and isinstance(arrival, bool) and (start is None or _valid_target(start))
                and all(value is None or isinstance(value, str) and 0 < len(value) <= 1024
                        for value in (port, record.get("sim_process"), record.get("arm")))):
            raise self.bad(number, "the job record's fields are not what armctl writes")
        # a later job record (a log resumed into itself) starts the job it records afresh
        self.header, self.frames, self.confirmed, self.done, self.cleared = record, Frames(), 0, 0, None
        self.resumed = None

    def tx(self, number: int, record: dict) -> None:
        frame = record.get("hex")
        if not _is_hex_frame(frame):
            raise self.bad(number, "a frame record without its frame")
        if "n" not in record:  # an abort or control frame of the host
            self.confirmed = len(self.frames)  # written after every job frame before it
            if self.frames and self.cleared is None:
                self.cleared = _clears(frame, self.header["control_on_arrival"], "the host")
            return
        n, line, at, after, target = (record.get(key) for key in ("n", "line", "at", "next", "target"))
        header = self.header
        from_line = header["from_line"]
        if not (_is_int(n) and _is_int(line) and _is_int(at) and (after is None or _is_int(after))
                and (target is None or _valid_target(target))):
            raise self.bad(number, "a frame record's fields are not what armctl writes")
        if n != len(self.frames) + 1:
            raise self.bad(number, f"frame {n} where frame {len(self.frames) + 1} was due")
        if not from_line <= at <= line or (after is not None and after < from_line):
            raise self.bad(number, f"frame {n} of line {line} says it continues at line {at} and after it at {after}")
        frames = self.frames
        if frames and (frames.nexts[-1] or None) != at:  # (a frame after the one that said it was the last too)
            raise self.bad(number, f"frame {n} starts at line {at} where the frame before it said {frames.nexts[-1] or None}")
        self.confirmed = len(frames)  # its record follows the write of the frame before
        frames.forget_targets_before(self.confirmed - 1)  # (the resume's candidates start at the frames confirmed)
        frames.append(line, at, after, target)
        if self.cleared is None:
            self.cleared = _clears(frame, header["control_on_arrival"], f"line {line}")

    def progress(self, number: int, record: dict) -> None:
        sent, done = record.get("frames_sent"), record.get("done_n")
        if not (_is_int(sent) and _is_int(done) and 0 <= done <= sent):
            raise self.bad(number, "a progress record's fields are not what armctl writes")
        if sent > len(self.frames):
            raise self.bad(number, f"a progress record counts {sent} frames written where the log holds "
                                   f"{len(self.frames)} frame records")
        self.confirmed, self.done = max(self.confirmed, sent), max(self.done, done)

    def point(self, notes: tuple) -> ResumePoint:
        header, words = self.header, self.words
        if header is None:
            # that run may itself have been a resume, or have started at a --from-line: "from the
            # start" would run again the lines an earlier run executed
            raise ResumeRefused("it has no job record: the run that wrote it stopped before its first frame, so no "
                                "frame of the job was sent (or an armctl that could not resume wrote it): start again "
                                f"the way that run started — from its start, at the line it started at "
                                f"({words.from_line}), or as a resume of the log that run resumed ({words.bare})")
        if header.get("sha256") != script_digest(self.data):  # the last job it records (runs may be appended)
            logged = header.get("script")
            same = "the same name" if logged == self.name else f"{logged!r}"
            raise ResumeRefused(f"it records {same} with other contents (sha256 {str(header.get('sha256'))[:12]}…, "
                                f"{self.name} is {script_digest(self.data)[:12]}…): the script was edited or is another one")
        if self.resumed is not None:  # the lines that resume ran would run a second time
            at, into = self.resumed["at"], self.resumed["into"]
            instead = (f"{words.naming(into)} instead (the log that resume wrote)" if into is not None else
                       f"that resume kept no log: {_by_hand(words)}")
            raise ResumeRefused(f"it was resumed already, at line {at}: resuming it again would run the lines that "
                                f"resume ran a second time; {instead}")
        return ResumePoint(header["from_line"], float(header["lead_s"]), self.frames, self.confirmed,
                           self.done, header["start"], self.cleared, notes, port=header.get("port"),
                           sim_process=header.get("sim_process"), arm=header.get("arm"), words=self.words)


def _clears(frame_hex: str, control_on_arrival: bool, who: str) -> str | None:
    """Why a control frame makes "every frame written ran" unprovable, or None."""
    from .protocol import PauseToggle, ResetArm, ResetConnector, decode_command

    try:
        command = decode_command(bytes.fromhex(frame_hex))
    except Exception:  # not a frame armctl can read: a motion frame of no known kind is none of these
        return None
    if isinstance(command, (ResetConnector, ResetArm)):
        return f"{who} sent a reset, which may have cleared frames queued behind it"
    if control_on_arrival and isinstance(command, PauseToggle):
        return f"{who} sent a pause toggle to an arm that acts on control frames as they land"
    return None


def read_resume_lines(lines: Iterable[str], name: str, data: bytes, log: str | None = None,
                      words=None) -> ResumePoint:
    """The resume point a ``--log`` records for the script ``name`` whose snapshot is ``data``,
    the log given line by line (each with its line break, the last without one if the log does
    not end with one: ``io.StringIO(text)`` gives a text so): a day's log is read as it streams
    by (``jobflow.read_resume_point``).  ``log``: its name, which a damaged line's message gives
    with the line's number; ``words``: how its refusals name a resume and a line (the interface's
    ``ResumeWords``; ``PlainWords`` by default)."""
    reader = _Reader(name, data, log, words)
    expected = 0  # each run's records count from 0 (a log may hold several runs, appended)
    for number, line in enumerate(lines, 1):
        complete = line.endswith("\n")
        line = line[:-1] if complete else line
        if not line.strip():
            continue
        record = unseal(line)
        if record is None:
            return _damaged(reader, line, number, not complete)
        seq = record.pop("seq", None)
        if not in_place(seq, expected):
            raise reader.bad(number, "a record out of its place (one dropped, moved or added)")
        expected = seq + 1
        reader.take(number, record)
    return reader.point(())


def _damaged(reader: _Reader, line: str, number: int, last: bool) -> ResumePoint:
    """A line that is no intact record: the crash's tear when it is the last and incomplete (no
    line break: a record made durable before its frame always has one), else a refusal."""
    if reader.header is None:
        if _old_record(line):
            raise ResumeRefused("it was written by an armctl before the checksummed journal (format 1): nothing "
                                f"in it tells a crash's cut from a corrupted record; {_by_hand(reader.words)}")
        if last and (number > 1 or line.startswith(_RECORD_START) or _RECORD_START.startswith(line)):
            return reader.point(())  # the job record torn by the crash: no job record, no frame sent
        raise ResumeRefused(f"line {number} is not an intact journal record: not a `run --log` file")
    if torn(line, not last):
        return reader.point(("the log's last line is torn (the crash's cut): ignored",))
    if last:
        raise reader.bad(number, "a whole record followed by other bytes where its line break belongs: the line "
                                 "break is damaged, not the crash's cut")
    raise reader.bad(number, f"the record is damaged ({damage_of(line)}) and is not the crash's cut "
                             "(a complete line)")


_RECORD_START = '{"t": '  # how every record of a log begins (its time first)


def _sealed_then_more(line: str) -> bool:
    """An intact record followed by something other than its line break: a cut leaves a strict
    prefix of a record (never a whole one with a byte after it), or a whole one followed only by
    NUL bytes (blocks the file system allocated and never wrote).  A flipped bit in the line
    break of the log's last record reads so — and that record's frame was written."""
    try:
        _, end = json.JSONDecoder().raw_decode(line)
    except (ValueError, RecursionError):
        return False
    return unseal(line[:end]) is not None and line[end:].strip("\0") != ""


def _old_record(line: str) -> bool:
    """A record of format 1: JSON with a ``dir``, no checksum."""
    try:
        record = json.loads(line)
    except (ValueError, RecursionError):
        return False
    return isinstance(record, dict) and "dir" in record and "crc" not in record


class Journal:
    """The journal's side of a running job: ``frame(statement, segment)`` gives the fields of the
    record of the frame about to be written (``frame_record``); ``update(view)`` writes a
    ``progress`` record through ``write`` (a dict → the log) when the frames written or known
    done change.  ``resume_at(statement)`` is the line ``--from-line`` would take to continue at
    ``statement`` (arcs, repeat blocks); ``peek()`` the statement after the one being written."""

    def __init__(self, write, resume_at, peek) -> None:
        self.write, self.resume_at, self.peek = write, resume_at, peek
        self._told = None
        self._at = None  # ``at`` of the last frame described

    def _continue_at(self, statement, before) -> int:
        if isinstance(statement.command, ArcEnd) and before is not None:
            return before  # a G301 cannot start a job: continue at its G300
        return self.resume_at(statement)

    def frame(self, n: int, statement, segment) -> dict:
        at = self._continue_at(statement, self._at if n > 1 else None)
        following = self.peek()
        after = None if following is None else self._continue_at(following, at)
        self._at = at
        target = None if segment is None else target_of(segment.kind, segment.end.xyz, segment.end.joints)
        return frame_record(n, statement.line, at, after, target)

    def update(self, view) -> None:
        done = view.last_done
        told = (view.frames_sent, view.frames_known_done)
        if told == self._told:
            return
        self._told = told
        self.write(progress_record(
            view.now_s - view.started_s, view.frames_sent, min(view.frames_known_done, view.frames_sent),
            None if view.last_sent is None else view.last_sent.line, None if done is None else done.line,
            None if view.first_not_done is None else self.resume_at(view.first_not_done)))
