"""The arm's worker: one thread that owns the link, and one job on it from the arm's report to
its ``RunResult`` (``run_job``).

Strategy: every write, every wait and the virtual clock of a ``sim://?clock=virtual`` port
belong to one thread (armctl/host/arm_tasks.py), which runs the API's tasks in order.  A job on it goes down,
never back up: read the arm (``jobflow.read_arm``; with a resume, the line the log and the
arm's report prove), plan the ``CheckedScript`` it was handed from the arm's report
(``checked.prepare``: a ``CheckedJob``), build the runner (``jobflow.start_job``), plug it into
the link and drive it (``jobflow.drive``), then the result.  Control of a running job from
other threads is a request to its engine (``JobControl``), carried out between two writes.
"""
from __future__ import annotations

import logging
from concurrent.futures import Future
from functools import partial
from dataclasses import dataclass
from typing import IO, Any, Callable

from .jobflow import JobFailed
from .results import Progress, RunResult

_logger = logging.getLogger("armctl.host.api")  # the API's logger: JobObserver's default goes there

PROGRESS_EVERY_S = 0.25  # on_progress is called at least this often (arm clock), even when nothing moved on
JOB_ENDED = object()  # a request the job ended before carrying out
PAUSE_READ_TIMEOUT_S = 3.0  # how long two agreeing pause reports are waited for (one comes every 0.27 s)


class ArmTimeout(JobFailed):
    """``timeout=`` passed before the arm proved the job done: the job was stopped as by
    ``Arm.stop`` (no more frames, the abort sequence) and ``result`` says how far it went."""


class JobObserver:
    """Follows one job as ``Arm.run(..., observer=)`` runs it — what ``armctl run`` builds its
    live panel, its ``--json`` events and its stderr notes from.  Subclass it and override what
    you need; every method is called from the arm's worker thread, and none may block for long
    (the job waits for it).  An exception raised by one stops the job, as ``on_progress``'s does.

    ``view`` is the job engine's live ``RunView`` (armctl/core/job.py): frames sent and known done,
    the last line sent and known executed, the pause state and the feed override, the arm's
    position, the ETA.  It changes while the job runs: read it in the call, do not keep it.
    """

    def started(self, view, plan) -> None:
        """Before the first frame: the job's ``view``, and its ``plan`` (``armctl.core.checked.CheckedJob``:
        ``start``, the arm's reported pose; ``initial``, the compiler's initial state — the
        panel's map is drawn from them and ``statements()``; ``estimate``; ``from_line``, after
        a ``resume`` the line the log proved)."""

    def update(self, view) -> None:
        """After every turn of the engine that wrote a frame, waited or ended (often: throttle)."""

    def note(self, text: str) -> None:
        """A message for people (resuming an arm found paused, the line a resume starts at,
        why a job is stopping).  Default: the ``armctl.host.api`` logger at INFO."""
        _logger.info("%s", text)

    def warning(self, diagnostic: Any) -> None:
        """A lint warning of the script (``Diagnostic``; errors raise ``ScriptError`` instead).
        Default: the ``armctl.host.api`` logger at INFO."""
        _logger.info("%s", diagnostic.render())



@dataclass(frozen=True)
class JobSpec:
    """What a call asked of one job, besides the script: its hooks, log, abort and resume."""

    observer: JobObserver
    on_progress: Callable[[Progress], None] | None = None
    timeout_s: float | None = None
    log: IO[str] | None = None
    abort: str = "pause"
    resume: Any = None  # a joblog.ResumePoint


class JobControl:
    """The job the worker is running, as the API's calls reach it: pause, resume and the feed
    override are requests to the job engine (``JobRunner.control``, carried out by the worker
    between two writes — the engine holds the feed while paused, in either control-frame mode);
    the timeout and ``on_progress`` are looked at whenever the runner reports (``on_update``)."""

    def __init__(self, runner, on_progress, timeout_s: float | None, observer: JobObserver | None = None,
                 journal: Callable[[Any], None] | None = None) -> None:
        self.runner = runner
        self.on_progress, self.timeout_s = on_progress, timeout_s
        self.observer, self.journal = observer, journal
        self.stop_asked = False  # stop() or the timeout: the runner was asked to stop
        self.timed_out = False
        self.callback_error: Exception | None = None  # what on_progress raised
        self._asked: list[Future] = []  # requests handed to the runner (answered JOB_ENDED if it ends first)
        self._shown: tuple = ()
        self._shown_s = float("-inf")

    def request(self, action: Callable[[Any], Any]) -> Future:
        """``action(job)`` on the worker at the runner's next turn; its answer in the Future.
        Called with ``Arm._lock`` held while this is the running job (``end`` runs under the
        lock too: a request is either carried out or answered ``JOB_ENDED``)."""
        future: Future = Future()
        self._asked.append(future)

        def carry_out(job) -> None:  # on the worker, at the runner's turn: the abort's turns too
            if future.done():
                return
            if self.stopping:  # a stop came after the request: it is not carried out
                future.set_exception(_stopped_first())
            else:
                future.set_result(action(job))

        self.runner.control(carry_out)
        return future

    @property
    def stopping(self) -> bool:
        """The job was asked to stop (``stop()``, the timeout) or its runner began to on its own."""
        return self.stop_asked or self.runner.stop_requested

    def request_stop(self, why: str | None = None) -> None:
        """The Ctrl-C path (``jobflow.drive`` sends the abort sequence); ``why`` goes into the
        result's messages.  Asked again while stopping: stop waiting for the arm (a second Ctrl-C)."""
        if why is not None and why not in self.runner.view.messages:  # two SIGTERMs: one note
            self.runner.view.messages.append(why)
        first = not self.stopping
        self.stop_asked = True
        if first:
            try:
                self.runner.request_stop()
                return
            except KeyboardInterrupt:  # the runner began stopping on its own meanwhile (a failure)
                pass
        self.runner.cut_short()  # stopping already (asked, the timeout, a failure): a second Ctrl-C

    def on_update(self, view) -> None:
        """The runner's hook, on the worker between two of its turns: the timeout, then
        ``on_progress`` (none once the job is stopping)."""
        if self.journal is not None:
            self.journal(view)  # --log's progress records, to the end (the abort included)
        if self.observer is not None:
            self._update_observer(view)  # the live view follows the abort too
        if self.stop_asked:
            return
        now_s = view.now_s
        if self.timeout_s is not None and now_s - view.started_s > self.timeout_s:
            self.timed_out = True
            self.request_stop()
            return
        if self.on_progress is not None:
            shown = (view.frames_sent, getattr(view.last_done, "line", None))
            if shown != self._shown or now_s - self._shown_s >= PROGRESS_EVERY_S:
                self._shown, self._shown_s = shown, now_s
                try:
                    self.on_progress(Progress.of(view, self.runner.job.arm_paused, now_s))
                except BaseException as error:  # stops the job (jobflow.drive); raised as the cause
                    self.stop_asked = True  # no callback while it aborts (sys.exit() too)
                    if isinstance(error, Exception):
                        self.callback_error = error
                    raise

    def _update_observer(self, view) -> None:
        """``observer.update``: an exception it raises stops the job, as ``on_progress``'s does;
        once the job is stopping, it is noted in the result instead — it must not cut the abort
        sequence short (the arm would run on with its queued frames)."""
        runner, observer = self.runner, self.observer
        if observer is None:
            return
        if not (self.stopping or runner.failure):
            observer.update(view)
            return
        try:
            observer.update(view)
        except Exception as error:
            told = f"the observer's update failed while the job stopped: {type(error).__name__}: {error}"
            if told not in view.messages:
                view.messages.append(told)

    def end(self) -> None:
        """The job is over: a request it did not carry out is done on the idle arm instead —
        unless the job stopped (its abort paused the arm: a resume then would run the frames it
        left queued), then it is refused, nothing sent."""
        stopped = self.stopping
        for future in self._asked:
            if future.done():
                continue
            if stopped:
                future.set_exception(_stopped_first())
            else:
                future.set_result(JOB_ENDED)
        self._asked = []


def _stopped_first():
    """What a pause, resume or feed request handed to a job that then stopped raises: the abort
    paused the arm, and a resume carried out now would run the frames it left queued."""
    from ..errors import ArmctlError

    return ArmctlError("the job stopped before it carried out this request: nothing was sent; ask again once "
                       "run() has returned")


def toggle_idle_arm(link, want_paused: bool) -> bool:
    """On the worker, no job running: one pause toggle when two agreeing reports say the arm is
    not yet as wanted (armctl/core/job_control.py's pause rule: a toggle on a guess could undo it),
    then wait for it to report so.  True when a toggle went; ``JobFailed`` when the reports do
    not agree or the arm does not follow."""
    from ..core.job_control import pause_toggle_needed
    from .jobflow import reported_pause
    from ..core.protocol import PauseToggle

    sent = pause_toggle_needed(want_paused, reported_pause(link, PAUSE_READ_TIMEOUT_S))
    if sent:
        link.write(PauseToggle().encode())
    if sent is None:
        raise JobFailed("the arm's pause reports did not agree twice in a row: no pause toggle sent")
    if sent and not link.wait_until(lambda s: s.paused is want_paused, PAUSE_READ_TIMEOUT_S):
        raise JobFailed(f"the arm did not report it {'paused' if want_paused else 'resumed'} after a pause toggle")
    return sent



@dataclass(frozen=True)
class ArmLine:
    """What a job needs of its arm: the link (the worker's), the profile and its motion model,
    the baud rate, the lead and how long to wait for the arm's status."""

    link: Any
    profile: Any
    model: Any
    baud: int
    lead_s: float
    status_timeout_s: float
    port: Any = None  # the PortChoice the arm was opened from, its arm read once (or its URL; None: the link's)


def run_job(arm: ArmLine, checked, spec: JobSpec, from_arm: bool, stopped: Callable[[], bool],
            attach: Callable[[JobControl], bool], detach: Callable[[JobControl], None]) -> RunResult:
    """On the worker: read the arm, plan ``checked`` (a ``CheckedScript``) from its report, drive
    the runner, report.  ``from_arm``: a move's one line, checked again from the arm's report (the
    words it leaves out are the arm's).  ``stopped()``: a ``stop()`` came since the call — before
    the first frame it ends the job with nothing sent.  ``attach(control)`` makes the job
    reachable by ``pause``/``stop`` (True: a stop came meanwhile); ``detach`` when it ended.
    An exception the observer raises before the first frame ends the job (``_BeforeFirstFrame``)."""
    early = _BeforeFirstFrame(spec.observer, checked.from_line if spec.resume is None else None)
    try:
        return _run_job(arm, checked, spec, from_arm, stopped, attach, detach, early)
    except _ObserverFailed as failed:
        raise JobFailed(f"the job ended failed: {failed.told}", failed.result) from failed.error


def _run_job(arm: ArmLine, checked, spec: JobSpec, from_arm: bool, stopped: Callable[[], bool],
             attach: Callable[[JobControl], bool], detach: Callable[[JobControl], None], early) -> RunResult:
    from ..core import checked as checking
    from .calibration import stale_notes
    from .jobflow import JournalFile, drive, journal_for, mark_resumed, read_arm, rest_wait_s, start_job
    from ..core.job import abort_frames

    link, observer = arm.link, spec.observer
    arrival = arm.profile.connector.control_on_arrival
    journal = None if spec.log is None else JournalFile(spec.log, sync=not getattr(link.clock, "virtual", False))
    # a resume decides from the arm as it is, paused or not: it continues or refuses before it sends anything
    state = read_arm(link, arm.status_timeout_s, journal, note=early.note, control_on_arrival=arrival,
                     unpause=spec.resume is None, stopped=stopped,
                     rest_s=None if spec.resume is not None else rest_wait_s(arm.status_timeout_s, arm.lead_s))
    if state is None:  # stop() (Ctrl-C) while an arm still moving was waited for: no frame goes
        return RunResult.interrupted_before_start(checked if spec.resume is None else None)
    if spec.resume is not None:
        resumed = _resume(arm, checked, spec, journal, stopped, early)
        if isinstance(resumed, RunResult):
            return resumed
        state, checked = resumed
    if from_arm:  # the move's words left out are the arm's: checked from its report
        checked = checking.check(checked.snapshot, arm.profile, checking.start_from_state(arm.model, state)[1])
        if checked.refusal() is not None:
            raise checked.refusal()
    for diagnostic in checked.diagnostics:  # for people, not the result (armctl run prints its own, before)
        if diagnostic.severity != "error":
            early.warning(diagnostic)
    job = checking.prepare(checked, arm.model, state, arm.lead_s, arm.baud)
    if job.estimate.frames == 0:
        where = f" from line {job.from_line}" if job.from_line > 1 else ""
        return RunResult.nothing_sent("finished", message=f"nothing to send: the script has no frames{where}")
    if stopped():  # stop() (Ctrl-C) while the arm was read: no frame goes
        return RunResult.interrupted_before_start(checked)
    runner = start_job(link, arm.model, job, journal)
    if journal is not None:  # which script it records (resume= checks it); a failed write stops the job like any
        _journal_job(runner, job, state, arrival, link.url if arm.port is None else arm.port)
    if spec.resume is not None and spec.resume.log_path is not None:  # a log is resumed once (jobflow.mark_resumed)
        into = getattr(spec.log, "name", None)
        runner.before_first_frame = partial(mark_resumed, spec.resume.log_path, job.from_line,
                                            into if isinstance(into, str) else None)
    control = JobControl(runner, spec.on_progress, spec.timeout_s, observer, journal_for(runner, job.snapshot, journal))
    runner.on_update = control.on_update
    link.on_status = runner.on_status  # the link's status frames go to this job's engine while it runs
    try:
        if attach(control):  # a stop() between the check above and here
            control.request_stop()
        early.started(runner, job)
        outcome = drive(runner, abort_frames(spec.abort, arrival), on_stopping=lambda why: observer.note(
            f"\narmctl: {why}: before the first frame, nothing was sent" if runner.job.stop.nothing_to_stop else
            f"\narmctl: {why}: no more frames are sent; sending the abort sequence ({spec.abort}) and waiting for "
            "the arm to come to rest …"))
    finally:
        detach(control)
        link.on_status = None
    view = runner.view
    from ..core.estimate import SD_PROGRAM_NOTE  # (here: a command that checks no script loads no compiler)

    time_held_overrun = None  # (see calibration.SLOWED_OVERRUN; an SD program's own time is not in the estimate)
    if (view.arm_time_s is not None and job.estimate.job_s > 0 and runner.streamer.capacity_held and view.frames_by_time
            and SD_PROGRAM_NOTE not in job.estimate.notes):
        time_held_overrun = view.arm_time_s / job.estimate.job_s - 1
    view.messages.extend(stale_notes(arm.profile, link.url, runner.streamer.slowest_proven,
                                     outcome == "frames may have been lost", time_held_overrun,
                                     moved_past_bound=runner.streamer.moved_past_bound))
    return _result(runner, outcome, job, control, spec)


class _ObserverFailed(Exception):
    """An observer's call before the first frame raised ``error`` (``run_job`` raises ``JobFailed``
    from it: not one itself, which the waits for the arm would take for their own)."""

    def __init__(self, told: str, result: RunResult, error: Exception) -> None:
        super().__init__(told)
        self.told, self.result, self.error = told, result, error


class _BeforeFirstFrame:
    """The observer's calls before the job's first frame — ``note`` and ``warning`` while the arm
    is read and the script checked, then ``started``.  An exception one raises ends the job there,
    nothing sent, the arm left as it is (no abort sequence: nothing of the job is queued) —
    ``JobFailed`` from it, outcome "failed", as an observer's exception stops a job; the job
    resumes at its first line (``from_line``; None: a resume's, which its log decides).  Ctrl-C or
    ``sys.exit()`` there leave ``run`` as raised."""

    def __init__(self, observer: JobObserver, from_line: int | None) -> None:
        self.observer, self.from_line = observer, from_line
        self.runner = self.job = None  # once built: the result is the runner's view's

    def note(self, text: str) -> None:
        self._call("note", text)

    def warning(self, diagnostic) -> None:
        self._call("warning", diagnostic)

    def started(self, runner, job) -> None:
        self.runner, self.job, self.from_line = runner, job, job.from_line
        self._call("started", runner.view, job)

    def _call(self, name: str, *args) -> None:
        try:
            getattr(self.observer, name)(*args)
        except Exception as error:
            told = f"the observer's {name}() raised {type(error).__name__}: {error}: nothing was sent"
            raise _ObserverFailed(told, self._result(told), error) from error

    def _result(self, told: str) -> RunResult:
        from dataclasses import replace

        if self.runner is None:
            result = RunResult.nothing_sent("failed", message=told)
        else:
            self.runner.view.messages.append(told)
            result = RunResult.of(self.runner.view, "failed", (), estimated_job_s=self.job.estimate.job_s)
        return replace(result, resume_line=self.from_line)


def _resume(arm: ArmLine, checked, spec: JobSpec, journal, stopped: Callable[[], bool], observer: _BeforeFirstFrame):
    """Wait for the arm to come to rest, then (its state, ``checked`` from the line the log and
    its report prove); a ``RunResult`` with nothing sent when a stop came or nothing is left."""
    from .jobflow import resume_paused, resume_start

    for told in spec.resume.notes:  # e.g. the torn last line a crash left, ignored
        observer.note(f"armctl: --resume: {told}")
    started = resume_start(arm.link, spec.resume, arm.status_timeout_s, arm.lead_s, stopped=stopped, note=observer.note)
    if started is None:  # stop() (Ctrl-C) while the arm ran out its queue: no frame goes
        return RunResult.interrupted_before_start()
    state, from_line, again = started
    if from_line is None:
        return _nothing_to_resume(arm, state)
    checked = checked.starting_at(from_line)
    if checked.from_line_error is not None:
        raise checked.from_line_error
    moved = spec.resume.moved_from(state.position_mm, tuple(state.joints_deg))
    observer.note(f"armctl: resuming {checked.name} at line {from_line}: the log and the arm's report prove every line "
                  "before it ran" + ("" if again is None else
                                     f"; it opens the repeat block the job stopped in (no job starts inside one), so "
                                     f"lines {from_line}–{again} of the passes already done run again")
                  + ("" if moved is None else
                     f"; the arm is not where line {moved} left it (moved since?): line {from_line} starts from where "
                     "it stands"))
    resume_paused(arm.link, arm.status_timeout_s, journal, observer.note, arm.profile.connector.control_on_arrival)
    return arm.link.snapshot()[0], checked


def _nothing_to_resume(arm: ArmLine, state) -> RunResult:
    """The arm rests where the log's last frame leaves it: the log's every line ran — proven only
    where the FIFO size is (``link.fifo_proven``), as at a job's end (core/job_end.py): else a frame
    a full FIFO dropped before the crash would look the same, and the resume ends unproven (exit 1).
    An arm the stop's abort paused is left so (nothing is sent), and the message says so."""
    from .link import fifo_proven
    from ..core.job_end import FIFO_UNMEASURED, PROBE_HINT

    paused = ("; the arm is paused, as the stop left it: the next job resumes it first" if state.paused else "")
    if fifo_proven(arm.link.url, arm.profile.connector):
        return RunResult.nothing_sent("finished", message=f"nothing to resume: every line of the job is proven executed{paused}")
    return RunResult.nothing_sent("finished, unproven", message=(
        f"nothing to resume: the arm is at rest where the log's last frame leaves it, but {FIFO_UNMEASURED} "
        f"(dropped before the crash); {PROBE_HINT}{paused}"))


def _journal_job(runner, job, state, arrival: bool, port) -> None:
    """The job's first record in ``--log``: which script, from which line and pose, on which port
    (a ``PortChoice`` or its URL), and which arm: its identity, read as the port was opened (a
    port kept open keeps its arm)."""
    from ..core.joblog import job_record, target_of
    from .resume_port import arm_of, simulator_process

    known = state.position_mm is not None and None not in state.joints_deg
    start = target_of("line", state.position_mm, state.joints_deg) if known else None
    url = getattr(port, "url", port)
    runner.log_record(job_record(job.snapshot.name, job.snapshot.data, job.from_line, job.lead_s, job.estimate.frames,
                                 arrival, start, url, simulator_process(url), arm_of(port)), durable=True)


def _result(runner, outcome: str, job, control: JobControl, spec: JobSpec) -> RunResult:
    """The ``RunResult``, returned for a job that finished or was interrupted, else raised."""
    result = RunResult.of(runner.view, outcome, job.snapshot.lines(), estimated_job_s=job.estimate.job_s)
    if control.timed_out:
        raise ArmTimeout(f"the arm did not prove the job done within {spec.timeout_s:g} s: it was stopped "
                         f"(last line known executed: {result.last_line_executed})", result)
    # "finished, unproven": the arm's reports say it ended, but the FIFO size was never probed
    # and some frames rest on time alone — returned, not raised (the arm did what it was told
    # as far as anyone can tell), with ``finished`` False and ``exit_code`` 1: the exit code
    # ``armctl run`` takes from this same result (one rule: ``exit_code_of``)
    if outcome not in ("finished", "finished, unproven", "interrupted"):
        detail = "; ".join(result.messages)
        raise JobFailed(f"the job ended {outcome}" + (f": {detail}" if detail else ""), result) from control.callback_error
    return result
