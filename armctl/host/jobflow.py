"""A job's steps around the runner, once, for ``armctl run`` and the Python API (armctl/host/api.py).

Strategy: the steps a careful operator takes on the arm, each a function that says what it
found and prints nothing — the caller decides how a finding is shown (``armctl run``: on
stderr, then exit 1; ``armctl.Arm``: an exception or a log record).  The script was checked
before (armctl/core/checked.py: ``check``, then ``prepare`` from the arm's report, a ``CheckedJob``);
here: read the arm (``read_arm``: every status kind, two more rotations, an arm that twice
reports it is paused resumed), build the runner of a ``CheckedJob`` (``start_job``) and drive it
(``drive``: one path for every way a job stops early — stop feeding, send the abort sequence,
wait for the arm — whoever asked).
A ``--log`` is a write-ahead journal (``JournalFile`` seals each of armctl/core/joblog.py's records
and fsyncs a frame's before the frame goes out; ``journal_for`` gives the records their fields)
that ``read_resume_point`` reads back and ``resume_start`` turns into the line to continue at,
from the arm's report — before anything is sent (``read_arm(unpause=False)``, then ``resume_paused``).
The pause rule — toggle only when two agreeing reports say the arm is in the other state — is
armctl/core/job_control.py's (the engine's); this module reads the reports it needs from the link.

Errors are ``JobFailed`` (the arm did not answer, or the job did not finish).
"""

from __future__ import annotations

import json
from typing import Any, Callable, Iterable

from ..errors import ArmctlError
from ..core.job_control import agreed_pause, pause_toggle_needed

READ_ROTATIONS = 2  # after all nine status kinds: two more rotations (a corrupted first frame of a kind replaced, H9)
AGREE_ROTATIONS = 4  # then up to this many more, until two states a rotation apart agree on the pose (``agreed_state``)


class JobFailed(ArmctlError):
    """The job could not start or did not finish; ``result`` (an ``armctl.RunResult``, or None
    when nothing was sent) says how far it went."""

    def __init__(self, message: str, result: Any = None) -> None:
        super().__init__(message)
        self.result = result


def read_arm(link, timeout_s: float, log=None, note: Callable[[str], None] = lambda text: None,
             control_on_arrival: bool = False, unpause: bool = True, rest_s: float | None = None,
             stopped: Callable[[], bool] | None = None):
    """Wait for all nine status kinds and two more rotations (so a corrupted first frame of a kind has
    been replaced or held back, H9); with ``unpause``, resume an arm that twice reports it is paused
    (``resume_paused``).  The arm's state; ``JobFailed`` when it does not answer.  ``log``: a
    ``JournalFile`` (or a text file) the frames sent are journalled to.  ``rest_s``: an arm still moving
    after ``agreed_state`` (frames queued before this job) is waited for until it rests, at most ``rest_s``
    (``rest_wait_s``; ``note`` told once reports show motion: ``MotionSeen``), None when ``stopped()``
    comes first; None: the job plans from its latest report (a resume waits: ``resume_start``)."""
    if not link.wait_until(lambda s: s.complete, timeout_s):
        raise JobFailed(f"{link.silence_message(timeout_s)}; nothing was sent")
    first = link.snapshot()[0]
    wait_rotations(link, READ_ROTATIONS - 1, timeout_s)
    earlier = link.snapshot()[0]
    wait_rotations(link, 1, timeout_s)
    if unpause and resume_paused(link, timeout_s, log, note, control_on_arrival):
        first = earlier = None
    state, agreed = agreed_state(link, earlier, timeout_s)
    # Any reading changed since the first (not only beyond jitter: F10 moves 0.05 mm a rotation): the arm may still run
    # frames queued before this job (another program, an armctl killed mid-job).  Planned from a moving arm, the job's frames
    # were timed from when they land, not from when that queue ends ("unproven", the arm's speed blamed).
    if rest_s is None or (agreed and (first is None or _pose(first) == _pose(state))):
        return state
    seen: list = []  # said once motion is seen: a first report corrupted within reach (H9) differed too, on a still arm

    def moving() -> None:
        seen.append(True)
        note("armctl: the arm is moving (frames queued before this job still running? another program, an armctl stopped "
             "without its abort sequence; or a line so noisy every report differs): waiting for it to come to rest before the job is planned")

    try:
        state = wait_for_rest(link, rest_s, stopped, moving)
    except JobFailed:
        if seen:
            raise JobFailed(f"the arm did not come to rest within {rest_s:g} s; "
                            f"{'nothing' if first is not None else 'only the pause toggle that resumed it'} was sent (frames "
                            "queued before this job may still be running: once the arm is still, run the job again; a longer "
                            "status timeout or lead waits longer)") from None
        note(f"armctl: in {rest_s:g} s the arm's reports never held still long enough to prove it at rest, and none "
             "showed it move (a noisy line?): the job is planned from where they agree it stands")
        state = agreed_state(link, link.snapshot()[0], timeout_s)[0]  # only corrupted reports: as before the wait
    if state is not None and unpause and resume_paused(link, timeout_s, log, note, control_on_arrival):
        state = link.snapshot()[0]  # a PAUSE queued behind what ran (another host's stop) paused it at rest
    return state


def rest_wait_s(timeout_s: float, lead_s: float) -> float:
    """How long a job waits for an arm still running what was queued before it (``read_arm``,
    ``resume_start``): the status timeout, twice a host's lead (an armctl's own queue when it
    died) and the engine's slack for an arm coming to rest."""
    from ..core.job import SETTLE_SLACK_S

    return timeout_s + 2 * lead_s + SETTLE_SLACK_S


def agreed_state(link, earlier, timeout_s: float):
    """The arm's state once it and the one a rotation before (``earlier``) agree on its position and joints
    within a reading's jitter, so that no one report becomes the job's start pose: a corrupted one the
    plausibility test lets through (a jump within reach: 2.3 mm of X on ``sim://?…&corrupt=0.02&seed=22``) had
    the first move planned from where the arm was not, and a target it refused there counted done by time
    ("finished").  At most ``AGREE_ROTATIONS`` rotations more.  (state, whether two agreed)."""
    from ..core.job_readings import moved_clearly

    state = link.snapshot()[0]
    for _ in range(AGREE_ROTATIONS):
        if earlier is not None and not moved_clearly(_pose(earlier), _pose(state)):
            return state, True
        earlier = state
        wait_rotations(link, 1, timeout_s)
        state = link.snapshot()[0]
    return state, False


def _pose(state) -> tuple:
    joints = tuple(state.joints_deg)
    return state.position_mm, joints[:3], joints[3:]


def resume_paused(link, timeout_s: float, log=None, note: Callable[[str], None] = lambda text: None,
                  control_on_arrival: bool = False) -> bool:
    """Resume an arm that twice reports it is paused, as its control mode needs
    (``job.resume_frames``: on an arm that acts on control frames as they land, a RESET
    CONNECTOR first, so nothing left queued runs twice), and let a move the pause froze finish,
    so the start pose is where the arm rests (``note`` is told).  Each frame's record is durable
    before the frame is written.  True when it resumed the arm."""
    from ..core.job import resume_frames

    if not _paused_twice(link, timeout_s):
        return False
    commands = resume_frames(control_on_arrival)
    note("armctl: the arm reports it is paused: sending " + (
        "a reset host connector (it acts on control frames as they land: nothing left queued runs twice) and "
        if len(commands) > 1 else "") + "one pause toggle to resume it")
    for command in commands:
        frame = command.encode()
        if log is not None:
            record = {"t": 0.0, "dir": "tx", "hex": frame.hex(), "resume": True}
            if hasattr(log, "append"):
                log.append(record, durable=True)
            else:
                log.write(json.dumps(record) + "\n")
        link.write(frame)
    if not link.wait_until(lambda s: s.paused is False, max(timeout_s, 1.0)):
        raise JobFailed("the arm stayed paused after a pause toggle; nothing else was sent")
    wait_rotations(link, 1, timeout_s)
    if control_on_arrival:
        _wait_still(link, timeout_s)
    return True


class JournalFile:
    """``--log`` as the journal writes it (armctl/core/joblog.py): each record sealed (its place and
    CRC-32) on a line of its own; ``append(record, durable=True)`` returns once the line is
    flushed and fsynced (a frame's record, before the frame goes to the port).  A file object
    without a descriptor (``io.StringIO``) or not a regular file (``/dev/null``, a pipe) is
    flushed only, and so is every record when ``sync``
    is False: an arm on a virtual clock (``sim://?clock=virtual``) lives in the host's process
    and its time moves only with the host, so nothing of it runs on after a crash — and an
    fsync a frame would cost a virtual job more wall time than the job itself.  The first fsync
    also fsyncs the log's directory, once: a file the run created survives a power cut only
    with its directory entry (POSIX; SQLite and PostgreSQL do the same)."""

    def __init__(self, file, sync: bool = True) -> None:
        self.file = file
        self.name = getattr(file, "name", "the log")
        self.seq = 0
        self.sync_each = sync
        self._directory_synced = False

    def append(self, record: dict, durable: bool = False) -> None:
        from ..core.joblog import seal

        self.file.write(seal(record, self.seq) + "\n")
        self.seq += 1
        if durable:
            self.sync()

    def sync(self) -> None:
        """Flushed, and fsynced when that is owed (``sync``)."""
        flush = getattr(self.file, "flush", None)  # any object with ``write`` may stand for the file
        if flush is not None:
            flush()
        if self.sync_each:
            self._fsync()

    def _fsync(self) -> None:
        import os
        import stat

        try:
            descriptor = self.file.fileno()
        except (AttributeError, OSError, ValueError):  # no descriptor (io.StringIO): flushed is all there is
            return
        if not stat.S_ISREG(os.fstat(descriptor).st_mode):
            return  # written through (/dev/null, a pipe, a terminal): nothing to fsync, and fsync says EINVAL
        os.fsync(descriptor)
        if not self._directory_synced:
            self._directory_synced = True
            _fsync_directory_of(descriptor, self.name)


def _fsync_directory_of(descriptor: int, name) -> None:
    """fsync the directory holding the regular file open on ``descriptor`` (named ``name``);
    where a directory cannot be opened or fsynced (Windows, some file systems), the file's own
    fsync is all there is."""
    import os
    import stat

    if not isinstance(name, str) or not stat.S_ISREG(os.fstat(descriptor).st_mode):
        return  # a device (/dev/null), or a file object with no path
    try:
        directory = os.open(os.path.dirname(os.path.abspath(name)), os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(directory)
    except OSError:
        pass
    finally:
        os.close(directory)


RESUME_SETTLE_S = 120.0  # the longest a move frozen by a pause may take to finish after the resume


def _wait_still(link, timeout_s: float) -> None:
    """Until the move a pause froze has finished (the arm at rest), at most ``RESUME_SETTLE_S``."""
    try:
        wait_for_rest(link, RESUME_SETTLE_S)
    except JobFailed:
        raise JobFailed(f"the arm did not come to rest within {RESUME_SETTLE_S:g} s of the resume; "
                        "nothing else was sent") from None


def wait_for_rest(link, timeout_s: float, stopped: Callable[[], bool] | None = None,
                  moving: Callable[[], None] | None = None):
    """The arm's state once its position and joints stayed the same for ``REST_CHECK_S``, each
    kind re-read in that time (armctl/core/evidence.py's rule of rest, the engine's own:
    ``still_long_enough``), and no SD program's run position advanced in it (an arm standing
    still in a program is at work, as at a job's end: ``Arrival.arm_at_rest``); ``JobFailed`` after
    ``timeout_s``; None as soon as ``stopped()`` says a stop was asked (Ctrl-C while a resume
    waits: nothing was sent, nothing is owed).  ``moving()`` (returning None) is called once the
    reports show it at work (``evidence.MotionSeen``; an SD program's run position too)."""
    from ..core.evidence import MotionSeen, still_long_enough
    from ..core.protocol import JointsHighStatus, JointsLowStatus, PositionStatus, RunPositionStatus

    kinds = (PositionStatus.KIND, JointsLowStatus.KIND, JointsHighStatus.KIND)
    deadline = link.clock() + timeout_s
    program = RunPositionStatus.KIND  # an SD program at work shows as motion does (``moving``)
    reading, since, seen = None, link.clock(), MotionSeen((*kinds, program))
    while True:
        if stopped is not None and stopped():
            return None
        state = link.snapshot()[0]
        now = link.clock()
        read_s = [state.last_seen.get(kind, float("-inf")) for kind in kinds]  # -inf: never read
        readings = (*_pose(state), state.run_position)  # one value per kind, as ``MotionSeen`` reads them
        if moving is not None and seen.read(readings, (*read_s, state.last_seen.get(program))):
            moving()
            moving = None  # said once
        if readings != reading:
            reading, since = readings, now
        elif still_long_enough(since, read_s):
            return state
        if now >= deadline:
            raise JobFailed(f"the arm did not come to rest within {timeout_s:g} s; nothing was sent")
        link.wait_until(lambda _state: False, 0.05)


def wait_rotations(link, rotations: int, timeout_s: float) -> None:
    frames = link.snapshot()[3]
    link.wait_until(lambda s: s.frames >= frames + 9 * rotations, timeout_s)


def reported_pause(link, timeout_s: float, reports: int = 3) -> bool | None:
    """The arm's pause state as two consecutive pause reports agree on it (the reader's state,
    so a held-back corrupt frame never counts), starting with the last one read; None when no
    two agree within ``reports`` reports, or the next does not come within ``timeout_s``."""
    read: list = []
    now = link.snapshot()[0]
    seen = now.last_seen.get(4)
    if seen is not None:
        read.append(now.paused)
    for _ in range(reports):
        if agreed_pause(read) is not None:
            break
        if not link.wait_until(lambda s: s.last_seen.get(4) != seen, timeout_s):
            break
        now = link.snapshot()[0]
        seen = now.last_seen.get(4)
        read.append(now.paused)
    return agreed_pause(read)


def _paused_twice(link, timeout_s: float) -> bool:
    """Paused in two consecutive pause reports: one flipped byte must not make armctl toggle.
    An arm whose last report says it runs needs no toggle to run: no second report is waited for."""
    if not link.snapshot()[0].paused:
        return False
    return pause_toggle_needed(want_paused=False, agreed=reported_pause(link, timeout_s)) is True


def start_job(link, model, job, log=None):
    """The runner that streams ``job`` (a ``checked.CheckedJob``; not started: call ``run``)."""
    from .link import control_frames_proven, fifo_proven
    from .runner import JobRunner
    from ..core.job import RunView
    from ..core.protocol import frame_seconds
    from ..core.streamer import Streamer

    estimate = job.estimate
    streamer = Streamer(model, job.start, lead_s=job.lead_s, baud=job.baud)
    view = RunView(total_frames=estimate.frames, estimated_job_s=estimate.job_s, total_lines=job.total_lines,
                   lead_s=job.lead_s, capacity=streamer.limit_frames, remaining_motion_s=estimate.motion_s,
                   frame_s=frame_seconds(job.baud))
    # ``done`` needs a FIFO size that is proven (probed, or a simulator known to hold it): link.fifo_proven;
    # and, for a job that sends control frames, how the arm takes them: link.control_frames_proven
    connector = model.profile.connector
    return JobRunner(link, streamer, Lookahead(job.statements()), view, log=log,
                     fifo_proven=fifo_proven(link.url, connector),
                     control_frames_proven=control_frames_proven(link.url, connector))


def drive(runner, abort_sequence: tuple, on_stopping: Callable[[str], None] = lambda why: None) -> str:
    """Run the job to its end, and make every other ending take one path: Ctrl-C (the runner's
    ``request_stop``), a failure the runner met (``runner.failure``) or any error mid-job stops
    the feeding, tells ``on_stopping`` why, sends ``abort_sequence`` and waits for the arm to
    come to rest.  Only a lost port skips the abort (there is nothing to send it through).
    The outcome: "finished", "interrupted", "failed", "port lost" or "no confirmation"."""
    from ..errors import PortError

    view = runner.view
    leaving: BaseException | None = None  # sys.exit() in a callback: the arm is stopped first, then it goes on
    try:
        runner.run()
        return view.outcome
    except KeyboardInterrupt:
        pass  # Ctrl-C, or a failure the runner met (runner.failure) that asked it to stop
    except PortError as error:
        view.messages.append(str(error))
        return "port lost"
    except Exception as error:  # anything else mid-job: the same path as Ctrl-C
        runner.fail(f"{type(error).__name__}: {error}")
    except BaseException as error:  # SystemExit, GeneratorExit: the same path, then raised again
        runner.fail(f"{type(error).__name__}: {error}")
        leaving = error
    try:  # a caller's hook that fails here must not keep the abort sequence from going
        on_stopping(runner.failure or "interrupted")
    except Exception as error:
        view.messages.append(f"while stopping: {type(error).__name__}: {error}")
    try:
        runner.abort(abort_sequence)
    except KeyboardInterrupt:  # a second Ctrl-C (Arm.stop again): the wait for rest ends here
        view.messages.append(_wait_cut_short(runner.job))
    except Exception as error:  # the abort itself failed: say so, the summary still follows
        view.messages.append(f"the abort did not complete: {type(error).__name__}: {error}")
    if runner.job.outcome is None and runner.failure:  # the abort was cut short: the engine did not end it
        view.outcome = "failed"
        view.messages.append(runner.failure)
    if leaving is not None:
        raise leaving
    return view.outcome  # "interrupted", "failed", or "port lost" if the abort could not be sent


WAIT_CUT_SHORT = "the wait for the arm to come to rest was cut short"  # (run's summary adds how to resume)


def _wait_cut_short(job) -> str:
    """What the summary says when the abort's wait for the arm was stopped: the arm may run on
    through what was sent (all of it, if the abort sequence did not go)."""
    sent = getattr(job.view.last_sent, "line", None)
    what = "what was sent" if sent is None or job.view.total_lines <= 1 else f"what was sent, up to line {sent}"
    unsent = " (the abort sequence was not all sent)" if job.stop.frames else ""
    return f"{WAIT_CUT_SHORT}{unsent}: it may still be running {what}: let it come to rest before going on"


def read_resume_point(log, script, from_line: int = 1, words=None):
    """The resume point a ``--log`` (a path, or a ``joblog.ResumePoint`` already read) records
    for this very ``script`` — read bounded, as every input; ``ResumeRefused`` (exit 2) for
    another script, an edited one, a file that is no log (or no regular file), a ``from_line`` given as well, or a
    job on a simulated arm of another process (``resume_port.refuse_gone_simulator``), told in
    ``words`` (``resume_words``: the interface's; the API's by default)."""
    import os
    from dataclasses import replace

    from ..errors import ResumeRefused
    from .inputs import MAX_LOG_BYTES, NotARegularFile, open_regular, read_lines_bounded
    from .log_lock import IN_USE, journal_in_use
    from ..core.joblog import ResumePoint, read_resume_lines
    from .resume_port import refuse_gone_simulator
    from .resume_words import API

    words = words or API
    if from_line != 1:
        named = words.naming(log.log_path if isinstance(log, ResumePoint) else log)
        raise ResumeRefused(f"{named}: the log decides the line to continue at: drop {words.from_line}")
    if isinstance(log, ResumePoint):
        refuse_gone_simulator(log, words)
        return log if log.words is not None else replace(log, words=words)  # (read by another interface: its words)
    name, named = str(log), words.naming(log)
    try:  # bounded: an endless file is an error, not a hang; a device (/dev/zero) is no log (open_regular)
        with open_regular(name, named) as stream:
            if journal_in_use(name):
                raise ResumeRefused(IN_USE)
            lines = (raw.decode("utf-8", errors="replace")
                     for raw in read_lines_bounded(stream, named, MAX_LOG_BYTES))
            point = read_resume_lines(lines, script.name, script.data, name, words)
        if not os.access(name, os.W_OK):
            raise ResumeRefused("it cannot be written, and a resume marks the log it continues so that it is never "
                                "resumed twice (mark_resumed): make it writable, or resume a writable copy")
        point = replace(point, log_path=name)
    except ResumeRefused as error:
        raise ResumeRefused(f"{named}: {error}") from None
    except NotARegularFile as error:  # a directory, a pipe, a device: no log (named already: open_regular)
        raise ResumeRefused(str(error)) from None
    except OSError as error:
        raise ResumeRefused(f"{named}: {error.strerror or error}") from None
    refuse_gone_simulator(point, words)
    return point


def mark_resumed(path: str, at_line: int, into: str | None) -> None:
    """Append ``joblog.resumed_record`` to the log at ``path`` a resume continues (at ``at_line``,
    journalled to ``into``), durable — flushed and fsynced — before the resume's first frame goes,
    as a frame's record before the frame: a log is resumed once.  Only the intact prefix is kept:
    a torn last line (the crash's cut, or NUL bytes a file system allocated) is cut off first —
    its frame never went, its record was never durable — so the record follows a whole line."""
    import os

    from ..core.joblog import resumed_record, seal

    with open(path, "r+b") as log:
        end = keep = log.seek(0, os.SEEK_END)
        while keep > 0:  # back to the last line break, a block at a time (a log may be large)
            start = max(0, keep - 65536)
            log.seek(start)
            found = log.read(keep - start).rfind(b"\n")
            if found >= 0:
                keep = start + found + 1
                break
            keep = start
        if keep == 0:  # (no whole line: read_resume_point refuses such a log before this)
            raise OSError(f"{path} holds no whole record")
        if keep < end:
            log.truncate(keep)
        log.seek(keep)
        log.write((seal(resumed_record(at_line, into), 0) + "\n").encode())
        log.flush()
        os.fsync(log.fileno())


def resume_start(link, point, timeout_s: float, lead_s: float, stopped: Callable[[], bool] | None = None,
                 note: Callable[[str], None] = lambda text: None):
    """Wait for the arm to come to rest (it runs out what was queued when the host died; ``note``
    told once its reports show it at work), then the line its report proves: (the state to start
    from, the line, the last line that runs a second time — ``ResumePoint.repeated``: a repeat block
    started again — or None), or (state, None, None) when every line ran; ``joblog.NotProven`` when
    the report proves neither; None when ``stopped()`` came first (see ``wait_for_rest``)."""
    wait_s = rest_wait_s(timeout_s, max(point.lead_s, lead_s))
    try:
        state = wait_for_rest(link, wait_s, stopped, moving=lambda: note(
            "armctl: --resume: the arm is still at work (what was queued when the job stopped): waiting for it to come "
            "to rest before its report says where to resume"))
    except JobFailed:  # a move longer than the wait was in progress: safe to try again once it ends
        raise JobFailed(f"the arm did not come to rest within {wait_s:g} s; nothing was sent (a long move may still be "
                        "running: once the arm is still, run the resume again; a longer status timeout or lead waits longer)") from None
    if state is None:
        return None
    ran = point.frames_run(state.position_mm, tuple(state.joints_deg))
    return state, point.after(ran), point.repeated(ran)


def journal_for(runner, script, log) -> Callable[[Any], None] | None:
    """``--log``'s journal (armctl/core/joblog.py) on ``runner``: the fields of each job frame's
    record (written ahead of the frame by the runner) and the progress records, as a runner's
    ``on_update``; None without a log."""
    if log is None:
        return None
    from ..core.joblog import Journal

    blocks = BlockIndex(script.lines())

    def resume_at(statement) -> int:
        return (blocks.outermost_start(statement.line) or statement.line) if getattr(statement, "loop", ()) else statement.line

    statements = runner.job.statements
    journal = Journal(runner.log_record, resume_at, statements.peek if isinstance(statements, Lookahead) else lambda: None)
    runner.frame_fields = journal.frame
    return journal.update


class Lookahead:
    """An iterator that can tell its next item without taking it (``peek``): the journal's
    record of a frame, written before the frame, names the line that follows it."""

    _NONE, _END = object(), object()

    def __init__(self, items) -> None:
        self._items = iter(items)
        self._next = self._NONE

    def __iter__(self):
        return self

    def __next__(self):
        item = self._next
        if item is self._NONE:
            return next(self._items)
        self._next = self._NONE
        if item is self._END:
            raise StopIteration
        return item

    def peek(self):
        """The next item, or None at the end."""
        if self._next is self._NONE:
            self._next = next(self._items, self._END)
        return None if self._next is self._END else self._next


def resume_line(view, lines: Iterable[str]) -> int | None:
    """The line ``--from-line`` (or ``Arm.run(from_line=)``) should name to continue: the first
    line not known executed, or — as no job can start inside a repeat block — the opening line
    of the outermost block around it (its passes already done then run again)."""
    resume = view.resume_line()
    loop = getattr(view.first_not_done, "loop", None)
    if resume is not None and loop:
        return outermost_block_start(lines, resume) or resume
    return resume


class BlockIndex:
    """The outermost repeat blocks of a script, found in one pass (``lines``: the script's
    lines, e.g. ``ScriptSnapshot.lines()`` — the same text that was sent)."""

    def __init__(self, lines: Iterable[str]) -> None:
        self.blocks: list[tuple[int, int]] = []  # (first line, last line) of each outermost block, in order
        from ..lint.scan import block_line

        depth, start = 0, None
        for number, text in enumerate(lines, 1):
            match = block_line(text)
            if match is None:
                continue
            if match.group(1).lower() == "repeat":
                if depth == 0:
                    start = number
                depth += 1
            elif depth:
                depth -= 1
                if depth == 0 and start is not None:
                    self.blocks.append((start, number))

    def outermost_start(self, line: int) -> int | None:
        """The first line of the outermost block around ``line``, if any."""
        from bisect import bisect_right

        index = bisect_right(self.blocks, (line, float("inf"))) - 1
        if index >= 0 and self.blocks[index][0] <= line <= self.blocks[index][1]:
            return self.blocks[index][0]
        return None


def outermost_block_start(lines, line: int) -> int | None:
    """The opening line of the outermost repeat block around ``line``, if any."""
    return BlockIndex(lines).outermost_start(line)
