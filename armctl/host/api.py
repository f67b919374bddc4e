"""The Python API: ``from armctl import Arm`` — open an arm, move it, run a job, read it, pause it.

Strategy: the steps a job takes, once, going down (armctl/core/checked.py, then armctl/host/arm_worker.py and
armctl/host/jobflow.py), and ``armctl run`` is a client of this module, not a second host: a script is
checked once before anything leaves (``checked.check``: a ``CheckedScript``, which a caller that
checked it already hands in instead), the arm's report is read and the job planned from it (or,
with ``resume=``, from the line a ``--log`` and the arm's report prove), the runner streams it with
the streamer's pacing, journals it to ``log=`` and ends it by the engine's end-of-job rules, and
any early stop takes ``jobflow.drive``'s one path (stop feeding, the abort sequence, wait for the
arm). ``move`` writes ONE script line from its keywords and runs it as a job of one line: the same
compiler, lint checks and streamer, never a second encoder.  Nothing here prints: what a job has to
say goes to a ``JobObserver`` (its default: the ``armctl.host.api`` logger at INFO); ``armctl run``'s
observer draws the panel, the ``--json`` events and the notes on stderr (armctl/ui/run_job.py).

Threads: each ``Arm`` has one worker thread that owns its link — every write, every wait, and the
virtual clock of a ``sim://?clock=virtual`` port, which moves only while someone waits on it and so
must have one owner.  Public calls put a task on the worker's queue; a blocking call waits for its
task, ``move(wait=False)`` returns at once and its move streams while the caller goes on.  Tasks
run in order, so a later ``move``, ``run``, ``status``, ``wait`` or ``close`` sees every queued
move executed, each exactly once.  A queued move that fails cancels the moves queued after it (the
arm is no longer where they assume) and its error is raised by the next blocking call.  Control of
a running job (``pause``, ``resume``, ``toggle_pause``, ``feed_override`` — the run panel's keys
call these) is a request to the job engine that the worker carries out between two writes
(``JobRunner.control``); ``stop`` and a timeout take the Ctrl-C path (``JobRunner.request_stop``,
then ``jobflow.drive``'s abort; a second ``stop`` once the abort went, ``JobRunner.cut_short``) —
never a write from another thread.  Observers and ``on_progress`` run on the worker (a call there
that waits for the arm — ``run``, ``wait`` — would run inside the job: ``Tasks.refuse_on_worker``).  This module
is the façade: the values it returns are armctl/host/results.py's, its argument checks
armctl/host/arguments.py's, the worker and its queue armctl/host/arm_tasks.py's, a job on it
armctl/host/arm_worker.py's.  Nothing is module-level state: several arms work at once in one process.
No signal handler is installed (``armctl run`` installs its own, in the main thread only, and calls
``stop``).
"""
from __future__ import annotations

import contextlib
import os
from typing import IO, TYPE_CHECKING, Any, Callable, Union

from . import arguments as args
from ..core import checked as checking
from .arguments import MOVE_KEYWORDS, default_speed, move_line
from .arm_tasks import Tasks
from .arm_worker import JOB_ENDED, ArmLine, ArmTimeout, JobControl, JobObserver, JobSpec, run_job, toggle_idle_arm
from ..errors import ArmctlError, ResumeRefused
from .jobflow import JobFailed
from .results import ArmStatus, Progress, RunResult
from ..core.streamer import DEFAULT_LEAD_S

if TYPE_CHECKING:
    from ..core.joblog import ResumePoint
    from .profile import Profile

__all__ = ["Arm", "ArmStatus", "ArmTimeout", "JobFailed", "JobObserver", "Progress", "RunResult"]
_REEXPORTED = (MOVE_KEYWORDS, move_line)  # for their callers: armctl move, the server

STATUS_TIMEOUT_S = 3.0  # what `armctl run --timeout` waits for the arm's status by default
_MOVE_NAME = "<move>"
_HOME_NAME = "<home>"

ScriptSource = Union[str, "os.PathLike[str]"]


class Arm:
    """One arm on one port (``Arm.open``); a context manager that closes it.

    Every method is thread-safe; the link is driven by the arm's own worker thread.
    """

    def __init__(self, link, baud: int, profile, *, lead_s: float = DEFAULT_LEAD_S,
                 status_timeout_s: float = STATUS_TIMEOUT_S, port=None) -> None:
        """Use ``Arm.open``; this takes an open ``armctl.host.link.Link`` and owns it from now on
        (``port``: the ``PortChoice`` it was opened from, its arm read once; None: read when needed)."""
        from ..core.motion import MotionModel

        self._link, self._baud, self._profile = link, baud, profile
        self._port = link.url if port is None else port
        self._model = MotionModel(profile)
        self.lead_s, self.status_timeout_s = lead_s, status_timeout_s
        self._tasks = Tasks(link.url, link)  # the worker that owns the link, the queued moves, the running job

    @classmethod
    def open(cls, port: str | None = None, baud: int | None = None, profile: str | os.PathLike[str] | Profile | None = None,
             *, lead_s: float = DEFAULT_LEAD_S, status_timeout_s: float = STATUS_TIMEOUT_S,
             connect: Callable[..., tuple[Any, int]] | None = None) -> Arm:
        """Open the arm on ``port`` as the CLI resolves it: ``port``, else ``ARMCTL_PORT``, else
        ``port`` in armctl.toml (the project's, then yours), else the built-in simulator
        (``sim://``); ``baud`` and ``profile`` (a TOML path, or a ``Profile`` already loaded, used
        as it is) likewise.  A profile read here carries the ``[connector]`` settings of the arm
        on that port: what ``armctl probe`` stored for it (docs/probe.md), and armctl.toml's
        ``[connector]`` if it was measured on that arm (``armctl.host.calibration.arm_profile(port=…)``).
        Prints nothing.  ``connect``: the function that opens the port,
        ``connect(port, baud, profile=)`` → (an ``armctl.host.link.Link``, the baud rate; ``port`` an
        ``armctl.host.link.PortChoice``, resolved once) — default
        ``armctl.host.link.connect`` with no banner (``armctl run`` passes one that prints the
        simulator's banner; a benchmark one that records the frames written).
        Raises ``ConfigError`` (a bad setting), ``ProfileError`` or ``PortError``."""
        link, line_baud, loaded, choice = args.open_port(port, baud, profile, connect, lead_s, status_timeout_s)
        try:
            return cls(link, line_baud, loaded, lead_s=lead_s, status_timeout_s=status_timeout_s, port=choice)
        except BaseException:
            link.close()
            raise

    # --- the port ----------------------------------------------------------------------------

    @property
    def url(self) -> str:
        """The port's URL or device path."""
        return self._link.url

    @property
    def baud(self) -> int:
        return self._baud

    @property
    def profile(self) -> Profile:
        """The arm's profile: the one its checks, plans and summaries use (with this arm's kept
        calibration, ``armctl.host.calibration``)."""
        return self._profile

    @property
    def is_virtual(self) -> bool:
        """A ``sim://?clock=virtual`` port: model time moves only while the arm's worker waits."""
        return self._link.is_virtual

    def __enter__(self) -> Arm:
        return self

    def __exit__(self, kind, error, traceback) -> None:
        if error is not None:  # the block failed (or Ctrl-C): stop the arm rather than finish its queue
            self._tasks.stop_once()  # (a stop under way already is not asked twice: that cuts its wait short)
        self.close(_raise=error is None)

    def close(self, *, _raise: bool = True) -> None:
        """Wait for the queued moves (each executed exactly once), then close the port.
        Raises the error of a queued move that failed, after closing."""
        self._tasks.close(self._link, raise_deferred=_raise)

    # --- moving ------------------------------------------------------------------------------

    def move(self, *, x: float | None = None, y: float | None = None, z: float | None = None,
             a: float | None = None, b: float | None = None, c: float | None = None,
             j1: float | None = None, j2: float | None = None, j3: float | None = None,
             j4: float | None = None, j5: float | None = None, j6: float | None = None,
             u: float | None = None, v: float | None = None, s: float | None = None,
             t: int | None = None, h: int | None = None, f: float | None = None,
             wait: bool = True, timeout: float | None = None) -> RunResult | None:
        """Move with one script line built from the keywords (docs/language.md): ``G1`` with
        X Y Z (mm) A B C (deg), or ``G6`` with J1…J6 (deg) when a joint is given; ``f`` the speed
        (mm/min for G1, deg/s for G6), ``s`` the PWM pulse (µs), ``t`` its channel (G1), ``h``
        the smoothing (G6), ``u``/``v`` the external axes.  Absolute coordinates; words left
        out keep the arm's reported values.  Without ``f`` the move runs at the profile's
        default speed (``[speed] default_linear_mm_min``, or ``default_joint_deg_s`` for G6).

        ``wait=True``: returns when the arm's reports prove it at rest at the target (the
        ``RunResult``); ``timeout`` seconds of the arm's clock, counted from when the move
        starts, raises ``ArmTimeout``.  ``wait=False``: queued, returns None at once; the move
        streams from the worker while you go on.  A line with errors raises ``ScriptError``
        here, in both cases, and nothing is sent.
        """
        words = dict(x=x, y=y, z=z, a=a, b=b, c=c, j1=j1, j2=j2, j3=j3, j4=j4, j5=j5, j6=j6, u=u, v=v, s=s, t=t, h=h)
        line = move_line(**words, f=default_speed(self._profile, words) if f is None else f)
        return self._submit_line(_MOVE_NAME, line, timeout, wait)

    def home(self, *, wait: bool = True, timeout: float | None = None) -> RunResult | None:
        """Go to the profile's fixed pose 0 (``POSE 0``, control 30/5), as a job of one line:
        ``wait=True`` returns when the arm's reports prove it at rest there; ``timeout`` and
        ``wait=False`` as for ``move``."""
        return self._submit_line(_HOME_NAME, "POSE 0\n", timeout, wait)

    def run(self, script: ScriptSource, *, from_line: int = 1, on_progress: Callable[[Progress], None] | None = None,
            timeout: float | None = None, observer: JobObserver | None = None, log: IO[str] | None = None,
            abort: str = "pause", resume: str | os.PathLike[str] | ResumePoint | None = None) -> RunResult:
        """Lint ``script``, stream it, wait until the arm's reports prove it done.

        ``script``: a path (``pathlib.Path``, or a ``str`` without a line break) is read once
        (what was checked is what is sent); a ``str`` holding a line break is the script's text
        (a one-line script: end it with ``"\\n"``).  ``from_line`` starts at that line with the
        modal state the lines before it set (a ``RunResult.resume_line``).  ``on_progress`` is
        called from the worker thread with a ``Progress``; an exception it raises stops the job.
        ``timeout``: seconds of the arm's clock from the start of this job; raises ``ArmTimeout``.
        ``observer``: a ``JobObserver`` that follows the job (the live view, notes, warnings).
        ``log``: a text file the job's journal goes to as it runs (``armctl run --log``: every
        frame written and read, and the records ``resume`` reads after a crash).  ``abort``:
        what a stop sends after it stops feeding — "pause", "reset-connector" or "none"
        (``armctl run --abort``).  ``resume``: a ``--log`` of this very script (a path, or
        ``armctl.core.joblog.ResumePoint``): wait for the arm to come to rest, then continue at the
        line the log and the arm's report prove (``from_line`` must be left at 1).

        Raises ``ScriptError`` (the script's errors, nothing sent), ``JobFailed`` (the arm did
        not answer, the job ended "failed", "port lost" or "no confirmation"; ``.result``),
        ``ResumeRefused`` (a ``resume`` log of another script, of an earlier format, or the file
        ``log`` writes to; nothing sent), ``joblog.JournalDamaged`` and ``joblog.NotProven`` (a
        damaged journal; a line it and the arm's report do not prove; nothing sent).
        Returns the ``RunResult`` of a job that finished or that ``stop()`` interrupted.
        """
        from ..core.joblog import ResumePoint

        stops = self._tasks.stops  # a stop() from here on (while the script is read and checked) ends the job, nothing sent
        if abort not in ("pause", "reset-connector", "none"):
            raise ValueError(f"abort={abort!r} must be 'pause', 'reset-connector' or 'none'")
        if not isinstance(script, checking.CheckedScript):  # TypeError for anything else (a str may be the text itself)
            args.job_snapshot_type(script)
        args.in_range("from_line", from_line, "LINE_RANGE", whole=True)
        args.check_callable("on_progress", on_progress)
        args.check_observer(observer)
        args.check_log(log)
        resume = args.path_or_none("resume", resume, also=(ResumePoint,))
        source = args.job_snapshot(script)  # read once: a snapshot, or a script checked already
        snapshot = getattr(source, "snapshot", source)
        claim, resume = _claimed_resume(resume, log, snapshot, from_line, self._port)
        job = JobSpec(observer or JobObserver(), on_progress, timeout, log, abort, resume)
        with claim:
            result = self._submit(source, from_line, job, wait=True, from_arm=False, stops=stops)
        assert result is not None
        return result

    def wait(self) -> None:
        """Return when every move queued with ``wait=False`` has run (its error, if one failed)."""
        self._tasks.call(lambda: None, waiting="wait")

    # --- reading and control -----------------------------------------------------------------

    def status(self, timeout: float | None = None) -> ArmStatus:
        """The arm's decoded report, once every status kind has been seen (after the moves and
        the job asked for before it ran); ``JobFailed`` when it is not complete within
        ``timeout`` seconds (default ``status_timeout_s``)."""
        timeout_s = self.status_timeout_s if timeout is None else args.check_timeout(timeout, "STATUS_TIMEOUT_RANGE_S")
        return self._call(lambda: ArmStatus.of(_complete_state(self._link, timeout_s), self._link.clock()))

    def status_json(self, timeout: float | None = None, *, at_once: bool = False) -> dict:
        """The arm's decoded report with the keys of ``armctl status --once --json``, once every
        status kind has been seen (``JobFailed`` otherwise, within ``timeout`` seconds).  After
        everything queued on the worker — or, ``at_once``, read from the link's reader thread now,
        even while a job runs (a wall-clock port only: on a virtual clock model time moves only on
        the worker, so there it waits its turn all the same)."""
        timeout_s = self.status_timeout_s if timeout is None else args.check_timeout(timeout, "STATUS_TIMEOUT_RANGE_S")
        def read() -> dict:
            return _complete_state(self._link, timeout_s).to_json()
        self._tasks.check_open()  # (at_once reads the link here: a closed one would be waited for)
        return read() if at_once and not self.is_virtual else self._call(read)

    def pause(self) -> bool:
        """Pause the arm.  During a job (``run``, or a ``move`` with ``wait=False``) this asks
        the job engine, as the run panel's key does: the protocol's pause toggle, and no frame
        written until ``resume`` (in the ``queued`` control mode, H5, the arm pauses after the
        frames already queued).  On an idle arm the toggle is sent only when two agreeing
        reports say it runs (armctl/core/job_control.py's pause rule: a toggle on a guess could
        resume it), and the call returns once the arm reports it paused.  True when a pause was
        asked (a toggle goes), False when there is nothing to pause."""
        return self._set_paused(True)

    def resume(self) -> bool:
        """Resume: during a job, a pause asked with ``pause`` (the toggle goes first, then the
        job's frames); on an idle arm, an arm that reports it is paused.  True when a toggle goes."""
        return self._set_paused(False)

    def toggle_pause(self) -> bool:
        """The run panel's pause key: during a job, resume it if a pause was asked, else pause
        it — in one request to the engine, so two quick presses cannot both pause.  Returns
        True when a toggle goes; ``ArmctlError`` when no job is running (nothing is sent to an
        idle arm: use ``pause``/``resume``, which read its reports first)."""
        answer = self._tasks.ask_job(lambda job: job.resume() or job.pause())
        if answer is JOB_ENDED:
            raise ArmctlError(f"no job is running on {self.url}: nothing to pause")
        return answer

    def feed_override(self, percent: float, *, relative: bool = False) -> int:
        """Rescale the speed of the running job's frames not yet written, as the run panel's
        −/+ keys do: ``percent`` of the script's speeds, put on the engine's grid (10…200 %,
        in steps of 10: armctl/core/feed.py) and never past the profile's limits; the effect shows
        within the lead.  Returns the percentage in force.  The override lasts for this job
        only; ``ArmctlError`` when no job is running.  ``relative=True``: ``percent`` is added
        to the percentage in force, in the engine's turn (the panel's −/+ keys: ∓10)."""
        value = args.feed_percent(percent)  # here, not in the job: a number the engine cannot take must not end it "failed"
        answer = self._tasks.ask_job(lambda job: job.set_feed_override(value + (job.control.feed.percent if relative else 0)))
        if answer is JOB_ENDED:
            raise ArmctlError(f"no job is running on {self.url}: there is no feed to override")
        return answer

    def stop(self, why: str | None = None) -> None:
        """Stop as ``armctl run``'s Ctrl-C does: cancel the queued moves, stop feeding the running
        job, send the abort sequence (a pause toggle, not sent to an arm that reports it is
        paused) and wait for the arm; the job's ``run`` returns outcome "interrupted".  The next
        job resumes an arm left paused.  Nothing to stop: does nothing.  A job being read or
        planned when it comes, or not yet past its first frame, sends nothing — no abort sequence
        either: the arm is left as it was (outcome "interrupted").  ``why``: a note the
        result's ``messages`` carry (``armctl run``: "stopped by SIGTERM").  Called again while
        the job stops: the wait for the arm to come to rest is cut short (a second Ctrl-C)."""
        self._tasks.stop(why)

    # --- the worker --------------------------------------------------------------------------

    def _set_paused(self, want_paused: bool) -> bool:
        answer = self._tasks.ask_job((lambda job: job.pause()) if want_paused else (lambda job: job.resume()))
        if answer is not JOB_ENDED:
            return answer
        # no job running, or it ended before carrying the request out: ask the idle arm
        return self._call(lambda: toggle_idle_arm(self._link, want_paused))

    def _call(self, task: Callable[[], Any]) -> Any:
        return self._tasks.call(task)

    @property
    def _job(self) -> JobControl | None:
        """The running job's control, if any."""
        return self._tasks.job

    def _checked(self, source, from_line: int, from_arm: bool):
        """``source`` (a snapshot, or a ``CheckedScript``: ``armctl run`` hands one in) checked for this arm."""
        return checking.checked_for(source, self._profile, checking.start_at(self._model)[1] if from_arm else None, from_line)

    def _submit_line(self, name: str, line: str, timeout: float | None, wait: bool) -> RunResult | None:
        """A move's one line as a job: checked here from the profile's fixed pose, again on the
        worker from the arm's report."""
        from ..script import ScriptSnapshot

        return self._submit(ScriptSnapshot(name, line.encode("ascii")), 1, JobSpec(JobObserver(), timeout_s=timeout),
                            wait, from_arm=True, call="home" if name == _HOME_NAME else "move")

    def _submit(self, source, from_line: int, spec: JobSpec, wait: bool, from_arm: bool,
                stops: int | None = None, call: str = "run") -> RunResult | None:
        """Check ``source`` here (``ScriptError``, nothing sent), then run it on the worker.

        ``from_arm``: the script is a move's one line, whose words left out are the arm's; it
        is checked here from the profile's fixed pose (so a bad word fails at once, even with
        ``wait=False``), and again on the worker from the arm's report before it is sent.  A
        job (``run``) is checked as ``armctl run`` checks it: from nothing known.  ``stops``: the
        count of ``stop()`` calls when the call began (default: now) — one since then, during the
        check, ends the job with nothing sent, as one while the arm is read does."""
        tasks = self._tasks
        stops = tasks.stops if stops is None else stops
        args.check_timeout(spec.timeout_s)
        checked = self._checked(source, from_line, from_arm)
        if checked.refusal() is not None:
            raise checked.refusal()

        def job() -> RunResult:
            line = ArmLine(self._link, self._profile, self._model, self._baud, self.lead_s, self.status_timeout_s,
                           self._port)
            return run_job(line, checked, spec, from_arm, lambda: stops != tasks.stops,
                           lambda control: tasks.attach(control, stops), tasks.detach)

        if wait:  # (``call``: the method asked; Ctrl-C while it waits stops the job, Tasks.call)
            return tasks.call(job, waiting=call)
        tasks.queue(job, stops)
        return None


def _complete_state(link, timeout_s: float):
    """A copy of the link's state once every status kind has been seen (``JobFailed`` after
    ``timeout_s``; the link's ``PortError`` once the port went away): what ``status`` and
    ``status_json`` read."""
    if not link.wait_until(lambda s: s.complete, timeout_s):
        raise JobFailed(link.silence_message(timeout_s))
    if link.error is not None:  # complete long ago, then the port went away: the last report is not live
        raise link.error
    return link.snapshot()[0]


def _claimed_resume(resume, log, snapshot, from_line: int, port):
    """``Arm.run``'s ``resume=``: (the claim held while the job runs — no second resume of that log
    meanwhile, ``log_lock.resume_claim`` — and the ``ResumePoint``, read before anything is sent:
    ``ResumeRefused``, nothing sent; a log of a job on another arm than the one on ``port`` too);
    (a null claim, None) without one."""
    if resume is None:
        return contextlib.nullcontext(), None
    from .jobflow import read_resume_point
    from .log_lock import resume_claim, same_journal
    from .resume_port import refuse_another_arm
    from .resume_words import API

    if log is not None and same_journal(log, resume):
        raise ResumeRefused(f"log= is the journal resume= reads ({os.fspath(resume)}): give the resumed job a "
                            "log of its own; nothing was sent")
    point = read_resume_point(resume, snapshot, from_line, API)
    refuse_another_arm(point, port, "resume dataclasses.replace(the ResumePoint, port=arm.url, arm=None)", words=API)
    return resume_claim(resume, API), point
