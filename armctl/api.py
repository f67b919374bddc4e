"""The Python API: ``from armctl import Arm`` — open an arm, move it, run a job, read it, pause it.

Strategy: the steps a job takes, once (armctl/jobflow.py), and ``armctl run`` is a client of
this module, not a second host: a script is linted before anything leaves, the arm's report is
read and the job compiled from it (or, with ``resume=``, from the line a ``--log`` and the arm's
report prove), the runner streams it with the streamer's pacing, journals it to ``log=`` and
ends it by the engine's end-of-job rules, and any early stop takes ``jobflow.drive``'s one path
(stop feeding, the abort sequence, wait for the arm).  ``move`` writes ONE script line from its
keywords and runs it as a job of one line: the same compiler, lint checks and streamer, never a
second encoder.  Nothing here prints: what a job has to say goes to a ``JobObserver`` (its
default: the ``armctl.api`` logger at INFO); ``armctl run``'s observer draws the panel, the
``--json`` events and the notes on stderr (armctl/ui/run_job.py).

Threads: each ``Arm`` has one worker thread that owns its link — every write, every wait, and
the virtual clock of a ``sim://?clock=virtual`` port, which moves only while someone waits on
it and so must have one owner.  Public calls put a task on the worker's queue; a blocking call
waits for its task, ``move(wait=False)`` returns at once and its move streams while the caller
goes on.  Tasks run in order, so a later ``move``, ``run``, ``status``, ``wait`` or ``close``
sees every queued move executed, each exactly once.  A queued move that fails cancels the
moves queued after it (the arm is no longer where they assume) and its error is raised by the
next blocking call.  Control of a running job (``pause``, ``resume``, ``toggle_pause``,
``feed_override`` — the run panel's keys call these) is a request to the job engine that the
worker carries out between two writes (``JobRunner.control``); ``stop`` and a timeout take the
Ctrl-C path (``JobRunner.request_stop``, then ``jobflow.drive``'s abort; a second ``stop`` once
the abort went, ``JobRunner.cut_short``) — never a write from another thread.  Observers and
``on_progress`` run on the worker.  Nothing is module-level state: several arms work at once in
one process.  No signal handler is installed (``armctl run`` installs its own, in the main
thread only, and calls ``stop``).
"""
from __future__ import annotations

import logging
import math
import numbers
import os
import queue
import threading
from concurrent.futures import Future
from dataclasses import dataclass, field, fields
from decimal import Decimal
from typing import IO, TYPE_CHECKING, Any, Callable, Mapping, Union

from .errors import ArmctlError, ResumeRefused, ScriptError
from .jobflow import JobFailed
from .streamer import DEFAULT_LEAD_S

if TYPE_CHECKING:
    from .job import RunView
    from .jobflow import JobPlan
    from .joblog import ResumePoint
    from .profile import Profile

__all__ = ["Arm", "ArmStatus", "ArmTimeout", "JobFailed", "JobObserver", "Progress", "RunResult"]

_logger = logging.getLogger(__name__)

STATUS_TIMEOUT_S = 3.0  # what `armctl run --timeout` waits for the arm's status by default
PROGRESS_EVERY_S = 0.25  # on_progress is called at least this often (arm clock), even when nothing moved on
# feed_override()'s percent (or its step, relative=True): any number here is put on the engine's
# 10…200 % grid (armctl/feed.py); one far outside it is a mistake, not a wish for 200 %
FEED_OVERRIDE_RANGE_PERCENT = (-1000.0, 1000.0)
PAUSE_READ_TIMEOUT_S = 3.0  # how long two agreeing pause reports are waited for (one comes every 0.27 s)
_MOVE_NAME = "<move>"
_HOME_NAME = "<home>"
_TEXT_NAME = "<script>"
# move()'s keywords, in the order the line is written: Cartesian (G1) and joint (G6) words
_CARTESIAN = ("x", "y", "z", "a", "b", "c")
_JOINTS = ("j1", "j2", "j3", "j4", "j5", "j6")
_OTHER = ("u", "v", "t", "h", "s", "f")
MOVE_KEYWORDS = _CARTESIAN + _JOINTS + _OTHER  # Arm.move's words (``armctl move``'s too)

ScriptSource = Union[str, "os.PathLike[str]"]


class ArmTimeout(JobFailed):
    """``timeout=`` passed before the arm proved the job done: the job was stopped as by
    ``Arm.stop`` (no more frames, the abort sequence) and ``result`` says how far it went."""


@dataclass(frozen=True)
class RunResult:
    """How a job (or a move) ended — the one result: ``Arm.run`` returns it and ``armctl run
    --json`` prints it as its summary (``to_json``), both built by ``RunResult.of``.

    ``outcome``: "finished" (the arm's reports proved every frame executed), "finished, unproven"
    (the arm ended, but some frames rest on time alone and the FIFO size was never probed: a
    dropped frame would look the same), "interrupted" (``Arm.stop``, Ctrl-C), "failed", "port
    lost", "no confirmation", "frames may have been lost" or "paused by the script" (the script's own
    PAUSE paused the arm with lines still to run; ``resume_line`` is the line after it) (the API
    raises these five as ``JobFailed`` with this result attached); ``armctl run --json`` adds "refused" (the script's
    errors, nothing sent).  ``frames_by_reports`` / ``frames_by_time`` / ``frames_unseen``: the frames
    the arm's reports saw run, those confirmed by time alone (the slowest-arm bound), and those a
    report proves gone from the FIFO without seeing them run (a sighting on a later frame: a frame a
    full FIFO dropped would look the same).  Lines are the script's line numbers; the move of
    ``Arm.move`` is line 1.  ``last_line_executed``: the last line the arm's reports prove
    executed.  ``arm_time_s``: from the first frame to the arm at rest, in the arm's clock, to
    the millisecond (None when it did not come to rest at the end).  ``resume_line``: where
    ``run(..., from_line=)`` / ``--from-line`` continues the job (None when nothing is left);
    ``resume_command``: the ``armctl run`` command line that does it (None from the API: it
    knows no command line).  ``exit_code``: what ``armctl run`` exits with for this outcome.
    """

    outcome: str
    frames_sent: int
    total_frames: int
    last_line_sent: int | None
    last_line_executed: int | None
    arm_time_s: float | None
    estimated_job_s: float
    resume_line: int | None
    resume_command: str | None = None
    messages: tuple[str, ...] = ()
    exit_code: int = 0
    frames_by_reports: int = 0
    frames_by_time: int = 0
    frames_unseen: int = 0

    @property
    def finished(self) -> bool:
        return self.outcome == "finished"

    @classmethod
    def of(cls, view, outcome: str, lines, *, estimated_job_s: float,
           resume_command: Callable[[int], str] | None = None) -> RunResult:
        """The result of a job the runner drove: ``view`` its ``RunView``, ``lines`` the
        script's lines (the resume line moves out of repeat blocks), ``resume_command(line)``
        the command line that resumes it."""
        from .jobflow import resume_line

        resume = resume_line(view, lines) if outcome != "finished" else None
        arm_time_s = view.arm_time_s
        return cls(outcome, view.frames_sent, view.total_frames, getattr(view.last_sent, "line", None),
                   getattr(view.last_done, "line", None), None if arm_time_s is None else round(arm_time_s, 3),
                   estimated_job_s, resume, None if resume is None or resume_command is None else resume_command(resume),
                   tuple(view.messages), exit_code_of(outcome), view.frames_by_reports, view.frames_by_time,
                   view.frames_unseen)

    @classmethod
    def nothing_sent(cls, outcome: str, *, exit_code: int | None = None, message: str | None = None) -> RunResult:
        """A job that sent nothing: nothing left to send ("finished"), or (``armctl run``)
        refused, failed before the first frame, interrupted while starting."""
        return cls(outcome, 0, 0, None, None, None if outcome != "finished" else 0.0, 0.0, None,
                   messages=() if message is None else (message,), exit_code=exit_code_of(outcome) if exit_code is None else exit_code)

    def to_json(self) -> dict:
        """The result as a JSON object's fields (``armctl run --json``'s summary)."""
        return {f.name: list(value) if isinstance(value, tuple) else value
                for f in fields(self) for value in (getattr(self, f.name),)}


def _check_timeout(timeout_s: float | None, limits: str = "JOB_TIMEOUT_RANGE_S") -> float | None:
    """A ``timeout=`` is None or a number of seconds in its range (NaN or ±inf would never fire,
    or fire at once)."""
    return None if timeout_s is None else _in_range("timeout", timeout_s, limits)


def _in_range(name: str, value, limits: str, whole: bool = False) -> float:
    """``value`` if it is a number (a whole one if ``whole``) inside ``armctl.limits.<limits>``
    (the CLI's ranges), else ValueError naming it."""
    from . import limits as ranges

    low, high = getattr(ranges, limits)
    kinds = int if whole else (int, float)
    if isinstance(value, bool) or not isinstance(value, kinds) or not low <= value <= high:
        raise ValueError(f"{name}={value!r} must be a {'whole ' if whole else ''}number from {low:g} to {high:g}")
    return value


# --- the arguments a caller gives, checked before anything is opened or sent --------------------
# A wrong type met later — inside the worker, mid-job — would be an AttributeError from deep
# inside, or a job ended "failed" after frames went out.  Each check names the argument.

_OBSERVER_METHODS = ("started", "update", "note", "warning")


def _path_or_none(name: str, value, *, also: tuple = (), none_ok: bool = True) -> Any:
    """``value`` as a str path (``os.PathLike`` accepted), None (if ``none_ok``), or one of the
    types ``also``; TypeError naming the argument otherwise (an open file, a number, bytes)."""
    if (value is None and none_ok) or (also and isinstance(value, also)):
        return value
    if isinstance(value, (str, os.PathLike)):
        path = os.fspath(value)
        if isinstance(path, str):
            return path
    wanted = " or ".join(["a path (str or os.PathLike)", *(t.__name__ for t in also), *(["None"] if none_ok else [])])
    raise TypeError(f"{name} must be {wanted}, not {_kind(value)}")


def _kind(value) -> str:
    if hasattr(value, "write") or hasattr(value, "read"):
        return f"an open file ({type(value).__name__})"
    return type(value).__name__


def _check_callable(name: str, value) -> None:
    if value is not None and not callable(value):
        raise TypeError(f"{name} must be a function or None, not {_kind(value)}")


def _check_observer(observer) -> None:
    missing = [m for m in _OBSERVER_METHODS if not callable(getattr(observer, m, None))]
    if observer is not None and missing:
        raise TypeError(f"observer must be a JobObserver (with {', '.join(_OBSERVER_METHODS)}), not "
                        f"{_kind(observer)}: it has no {missing[0]}()")


def _check_log(log) -> None:
    """``log=`` is an open text file (the journal is written as the job runs), as ``open(path, "w")``
    gives: not a path (``armctl run --log`` opens one), not a binary file."""
    import io

    if log is None:
        return
    if isinstance(log, (str, bytes, os.PathLike)):
        raise TypeError(f"log must be an open text file such as open(path, 'w', encoding='utf-8'), not a path ({log!r})")
    if not callable(getattr(log, "write", None)):
        raise TypeError(f"log must be an open text file, not {_kind(log)}")
    if isinstance(log, (io.RawIOBase, io.BufferedIOBase)) or "b" in getattr(log, "mode", ""):
        raise TypeError("log must be a text file (open(path, 'w')), not a binary one: the journal is JSON lines of text")


def _check_connected(connected) -> tuple[Any, int]:
    """What ``connect`` returned: (a link, the baud rate), else TypeError (closing what it opened)."""
    if isinstance(connected, tuple) and len(connected) == 2 and callable(getattr(connected[0], "write", None)) \
            and isinstance(connected[1], int) and not isinstance(connected[1], bool):
        return connected
    for part in connected if isinstance(connected, tuple) else (connected,):
        close = getattr(part, "close", None)
        if callable(close):
            close()
    raise TypeError(f"connect must return (an armctl.link.Link, the baud rate), not {_short(connected)}")


def _short(value, limit: int = 80) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def exit_code_of(outcome: str) -> int:
    """What ``armctl run`` exits with after a job that ended ``outcome`` (docs/cli.md's codes)."""
    return 0 if outcome == "finished" else 130 if outcome == "interrupted" else 1


@dataclass(frozen=True)
class Progress:
    """What ``on_progress`` is given, from the worker thread, whenever a frame was written or
    the frames known executed moved on, and at least every ``PROGRESS_EVERY_S`` (times in the
    arm's clock)."""

    frames_sent: int
    total_frames: int
    last_line_sent: int | None
    last_line_executed: int | None  # the last line the arm's reports prove executed
    elapsed_s: float
    eta_s: float
    position_mm: tuple[float, float, float] | None
    paused: bool | None  # as two agreeing reports say (a pause toggle acts after the frames queued before it)


@dataclass(frozen=True)
class ArmStatus:
    """The arm's decoded report: every value as last accepted (None until its kind was seen),
    and ``ages_s``: for each group of values, seconds since it was last reported."""

    position_mm: tuple[float, float, float] | None
    joints_deg: tuple[float | None, ...]
    worktable_mm: tuple[float | None, ...]
    wrist_deg: tuple[float | None, float | None]
    pwm_us: int | None
    paused: bool | None
    run_position: float | None
    ages_s: Mapping[str, float | None] = field(default_factory=dict)


class JobObserver:
    """Follows one job as ``Arm.run(..., observer=)`` runs it — what ``armctl run`` builds its
    live panel, its ``--json`` events and its stderr notes from.  Subclass it and override what
    you need; every method is called from the arm's worker thread, and none may block for long
    (the job waits for it).  An exception raised by one stops the job, as ``on_progress``'s does.

    ``view`` is the job engine's live ``RunView`` (armctl/job.py): frames sent and known done,
    the last line sent and known executed, the pause state and the feed override, the arm's
    position, the ETA.  It changes while the job runs: read it in the call, do not keep it.
    """

    def started(self, view: RunView, plan: JobPlan) -> None:
        """Before the first frame: the job's ``view``, and its ``plan`` (``armctl.jobflow.JobPlan``:
        ``start``, the arm's reported pose; ``initial``, the compiler's initial state — the
        panel's map is drawn from them; ``estimate``; ``from_line``, after a ``resume`` the line
        the log proved)."""

    def update(self, view: RunView) -> None:
        """After every turn of the engine that wrote a frame, waited or ended (often: throttle)."""

    def note(self, text: str) -> None:
        """A message for people (resuming an arm found paused, the line a resume starts at,
        why a job is stopping).  Default: the ``armctl.api`` logger at INFO."""
        _logger.info("%s", text)

    def warning(self, diagnostic: Any) -> None:
        """A lint warning of the script (``Diagnostic``; errors raise ``ScriptError`` instead).
        Default: the ``armctl.api`` logger at INFO."""
        _logger.info("%s", diagnostic.render())


# status kinds behind each group of ArmStatus (armctl/protocol.py's STATUS_ROTATION)
_AGE_KINDS = {"position": (0,), "joints": (1, 2), "worktable": (3,), "pause_pwm": (4,), "wrist": (5,),
              "program": (100, 102, 103)}


_SKIPPED = object()  # a task not run: a queued move before it failed (its error is raised instead)
_JOB_ENDED = object()  # a request the job ended before carrying out


class _Worker:
    """One thread that runs tasks in order: the only one that touches the arm's link."""

    def __init__(self, name: str) -> None:
        self._tasks: queue.SimpleQueue = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._loop, name=name, daemon=True)
        self._thread.start()

    def submit(self, task: Callable[[], Any]) -> Future:
        future: Future = Future()
        self._tasks.put((task, future))
        return future

    def call(self, task: Callable[[], Any]) -> Any:
        """Run ``task`` on the worker and return its result (at once when already on it)."""
        if self.is_current():
            return task()
        return self.submit(task).result()

    def is_current(self) -> bool:
        return threading.current_thread() is self._thread

    def stop(self) -> None:
        self._tasks.put(None)
        if not self.is_current():
            self._thread.join()

    def _loop(self) -> None:
        while True:
            item = self._tasks.get()
            if item is None:
                return
            task, future = item
            if not future.set_running_or_notify_cancel():
                continue  # cancelled while queued (stop, or a queued move before it failed)
            try:
                future.set_result(task())
            except BaseException as error:  # handed to whoever waits; the worker goes on
                future.set_exception(error)


@dataclass(frozen=True)
class _JobSpec:
    """What a call asked of one job, besides the script: its hooks, log, abort and resume."""

    on_progress: Callable[[Progress], None] | None = None
    timeout_s: float | None = None
    observer: JobObserver = field(default_factory=lambda: JobObserver())
    log: IO[str] | None = None
    abort: str = "pause"
    resume: Any = None  # a joblog.ResumePoint


class _JobControl:
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
        self._asked: list[Future] = []  # requests handed to the runner (answered _JOB_ENDED if it ends first)
        self._shown: tuple = ()
        self._shown_s = float("-inf")

    def request(self, action: Callable[[Any], Any]) -> Future:
        """``action(job)`` on the worker at the runner's next turn; its answer in the Future.
        Called with ``Arm._lock`` held while this is the running job (``end`` runs under the
        lock too: a request is either carried out or answered ``_JOB_ENDED``)."""
        future: Future = Future()
        self._asked.append(future)
        self.runner.control(lambda job: future.done() or future.set_result(action(job)))
        return future

    def request_stop(self, why: str | None = None) -> None:
        """The Ctrl-C path (``jobflow.drive`` sends the abort sequence); ``why`` goes into the
        result's messages.  Asked again while stopping: stop waiting for the arm (a second Ctrl-C)."""
        if why is not None and why not in self.runner.view.messages:  # two SIGTERMs: one note
            self.runner.view.messages.append(why)
        first = not self.stop_asked and not self.runner.stop_requested
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
            self.observer.update(view)  # the live view follows the abort too
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
                    self.on_progress(_progress(view, self.runner.job.arm_paused, now_s))
                except Exception as error:  # stops the job (jobflow.drive); raised as the cause
                    self.callback_error, self.stop_asked = error, True  # no callback while it aborts
                    raise

    def end(self) -> None:
        """The job is over: a request it did not carry out is done on the idle arm instead."""
        for future in self._asked:
            if not future.done():
                future.set_result(_JOB_ENDED)
        self._asked = []


def _write_toggle(link) -> None:
    from .protocol import PauseToggle

    link.write(PauseToggle().encode())


def _check(script, profile, initial):
    """Lint ``script``: the report, or ``ScriptError`` with its errors."""
    from .jobflow import lint_script

    report = lint_script(script, profile, initial)
    if report.errors:
        raise ScriptError([d for d in report.diagnostics if d.severity == "error"], errors=report.errors)
    return report


def _progress(view, paused: bool | None, now_s: float) -> Progress:
    position = view.position_mm
    return Progress(view.frames_sent, view.total_frames, getattr(view.last_sent, "line", None),
                    getattr(view.last_done, "line", None), now_s - view.started_s, view.eta_s,
                    None if position is None else tuple(position), paused)


def _word(letter: str, value: float) -> str:
    """``X250`` — a word as the language reads it: no exponent, no ``inf``/``nan``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"move(): {letter.lower()} must be a number, not {type(value).__name__}")
    text = repr(value if isinstance(value, int) else float(value))  # the shortest text that reads back as the same float
    if text in ("inf", "-inf", "nan"):
        raise ValueError(f"move(): {letter.lower()}={text} is not a finite number")
    number = format(Decimal(text), "f")
    letter = letter.upper()
    return f"{letter}={number}" if letter.startswith("J") else f"{letter}{number}"


def default_speed(profile: Profile, words: Mapping[str, float | None]) -> float | None:
    """The F a move without ``f`` is sent with: the profile's ``[speed]`` default of the line's
    family (``default_joint_deg_s`` when a joint is named, else ``default_linear_mm_min``).
    None when no word is given (``move_line`` says what is missing)."""
    if all(value is None for value in words.values()):
        return None
    joint = any(words.get(name) is not None for name in _JOINTS)
    speed = profile.speed.default_joint_deg_s if joint else profile.speed.default_linear_mm_min
    return int(speed) if speed.is_integer() else speed


def move_line(**words: float | None) -> str:
    """The one script line ``Arm.move`` sends: G6 when a joint is named, else G1 (the
    compiler judges every word: a Cartesian word on G6, say, is its error, not ours)."""
    given = {name: value for name, value in words.items() if value is not None}
    unknown = sorted(set(given) - set(MOVE_KEYWORDS))
    if unknown:
        raise TypeError(f"move() got unexpected keyword arguments: {', '.join(unknown)}")
    if not given:
        raise ValueError("move() needs at least one word (x=…, j1=…, s=…, f=…)")
    code = "G6" if any(name in given for name in _JOINTS) else "G1"
    order = _JOINTS + _CARTESIAN + _OTHER if code == "G6" else _CARTESIAN + _JOINTS + _OTHER
    return " ".join([code] + [_word(name, given[name]) for name in order if name in given]) + "\n"


class Arm:
    """One arm on one port (``Arm.open``); a context manager that closes it.

    Every method is thread-safe; the link is driven by the arm's own worker thread.
    """

    def __init__(self, link, baud: int, profile, *, lead_s: float = DEFAULT_LEAD_S,
                 status_timeout_s: float = STATUS_TIMEOUT_S) -> None:
        """Use ``Arm.open``; this takes an open ``armctl.link.Link`` and owns it from now on."""
        from .motion import MotionModel

        self._link, self._baud, self._profile = link, baud, profile
        self._model = MotionModel(profile)
        self.lead_s, self.status_timeout_s = lead_s, status_timeout_s
        self._lock = threading.Lock()
        self._queued: list[Future] = []  # moves queued with wait=False, not yet finished
        self._deferred: BaseException | None = None  # the error of a queued move, for the next blocking call
        self._job: _JobControl | None = None
        self._stops = 0  # how many times stop() was called: a queued move from before it is not sent
        self._closed = False
        self._worker = _Worker(f"armctl-arm {link.url}")

    @classmethod
    def open(cls, port: str | None = None, baud: int | None = None, profile: str | os.PathLike[str] | Profile | None = None,
             *, lead_s: float = DEFAULT_LEAD_S, status_timeout_s: float = STATUS_TIMEOUT_S,
             connect: Callable[..., tuple[Any, int]] | None = None) -> Arm:
        """Open the arm on ``port`` as the CLI resolves it: ``port``, else ``ARMCTL_PORT``, else
        ``port`` in armctl.toml (the project's, then yours), else the built-in simulator
        (``sim://``); ``baud`` and ``profile`` (a TOML path, or a ``Profile`` already loaded, used
        as it is) likewise.  A profile read here carries the ``[connector]`` settings of the arm
        on that port: what ``armctl probe`` stored for it (docs/probe.md), and armctl.toml's
        ``[connector]`` if it was measured on that arm (``armctl.calibration.arm_profile(port=…)``).
        Prints nothing.  ``connect``: the function that opens the port,
        ``connect(port, baud, profile=)`` → (an ``armctl.link.Link``, the baud rate; ``port`` an
        ``armctl.link.PortChoice``, resolved once) — default
        ``armctl.link.connect`` with no banner (``armctl run`` passes one that prints the
        simulator's banner; a benchmark one that records the frames written).
        Raises ``ConfigError`` (a bad setting), ``ProfileError`` or ``PortError``."""
        from .calibration import arm_profile
        from .link import PortChoice, choose_port, connect as open_link
        from .profile import Profile

        # types and the CLI's ranges (armctl/limits.py), checked before the port opens
        port = _path_or_none("port", port, also=(PortChoice,))  # (a PortChoice: the CLI's port, resolved once)
        profile = _path_or_none("profile", profile, also=(Profile,))
        _check_callable("connect", connect)
        _in_range("lead_s", lead_s, "LEAD_RANGE_S")
        _in_range("status_timeout_s", status_timeout_s, "STATUS_TIMEOUT_RANGE_S")
        if baud is not None:
            _in_range("baud", baud, "BAUD_RANGE", whole=True)
        choice = choose_port(port)  # once: the arm's stored calibration is loaded for this port
        loaded = profile if isinstance(profile, Profile) else \
            arm_profile(None if profile is None else os.fspath(profile), port=choice.url)
        link, line_baud = _check_connected((open_link if connect is None else connect)(choice, baud, profile=loaded))
        try:
            return cls(link, line_baud, loaded, lead_s=lead_s, status_timeout_s=status_timeout_s)
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
        calibration, ``armctl.calibration``)."""
        return self._profile

    @property
    def is_virtual(self) -> bool:
        """A ``sim://?clock=virtual`` port: model time moves only while the arm's worker waits."""
        return self._link.is_virtual

    def __enter__(self) -> Arm:
        return self

    def __exit__(self, kind, error, traceback) -> None:
        if error is not None:
            self.stop()  # the block failed (or Ctrl-C): stop the arm rather than finish its queue
        self.close(_raise=error is None)

    def close(self, *, _raise: bool = True) -> None:
        """Wait for the queued moves (each executed exactly once), then close the port.
        Raises the error of a queued move that failed, after closing."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        try:
            self._worker.call(lambda: None)  # every task queued before has run
        finally:
            self._worker.stop()
            self._link.close()
        if _raise:
            self._raise_deferred()

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
        from .script import ScriptSnapshot

        return self._submit(ScriptSnapshot(_MOVE_NAME, line.encode("ascii")), 1, _JobSpec(timeout_s=timeout), wait, from_arm=True)

    def home(self, *, wait: bool = True, timeout: float | None = None) -> RunResult | None:
        """Go to the profile's fixed pose 0 (``POSE 0``, control 30/5), as a job of one line:
        ``wait=True`` returns when the arm's reports prove it at rest there; ``timeout`` and
        ``wait=False`` as for ``move``."""
        from .script import ScriptSnapshot

        return self._submit(ScriptSnapshot(_HOME_NAME, b"POSE 0\n"), 1, _JobSpec(timeout_s=timeout), wait, from_arm=True)

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
        ``armctl.joblog.ResumePoint``): wait for the arm to come to rest, then continue at the
        line the log and the arm's report prove (``from_line`` must be left at 1).

        Raises ``ScriptError`` (the script's errors, nothing sent), ``JobFailed`` (the arm did
        not answer, the job ended "failed", "port lost" or "no confirmation"; ``.result``),
        ``ResumeRefused`` (a ``resume`` log of another script, of an earlier format, or the file
        ``log`` writes to; nothing sent), ``joblog.JournalDamaged`` and ``joblog.NotProven`` (a
        damaged journal; a line it and the arm's report do not prove; nothing sent).
        Returns the ``RunResult`` of a job that finished or that ``stop()`` interrupted.
        """
        from .joblog import ResumePoint
        from .script.files import ScriptSnapshot, read_script

        stops = self._stops  # a stop() from here on (while the script is read and checked) ends the job, nothing sent
        if abort not in ("pause", "reset-connector", "none"):
            raise ValueError(f"abort={abort!r} must be 'pause', 'reset-connector' or 'none'")
        if not isinstance(script, ScriptSnapshot):  # TypeError for anything else (a str may be the text itself)
            _path_or_none("script", script, none_ok=False)
        _in_range("from_line", from_line, "LINE_RANGE", whole=True)
        _check_callable("on_progress", on_progress)
        _check_observer(observer)
        _check_log(log)
        resume = _path_or_none("resume", resume, also=(ResumePoint,))
        if isinstance(script, ScriptSnapshot):
            snapshot = script  # read once already (``armctl run`` reads stdin or the file itself)
        elif isinstance(script, str) and ("\n" in script or "\r" in script):
            snapshot = ScriptSnapshot(_TEXT_NAME, script.encode("utf-8", "surrogateescape"))
        else:
            path = os.fspath(script)
            try:
                snapshot = read_script(path)
            except OSError as error:
                hint = " (script text must hold a line break: end a one-line script with \\n)" if isinstance(script, str) else ""
                raise JobFailed(f"cannot read {path}: {error.strerror or error}{hint}; nothing was sent") from None
        if resume is not None:
            from .jobflow import read_resume_point, same_journal

            if log is not None and same_journal(log, resume):
                raise ResumeRefused(f"log= is the journal resume= reads ({os.fspath(resume)}): give the resumed job a "
                                    "log of its own; nothing was sent")
            resume = read_resume_point(resume, snapshot, from_line)  # before anything: ResumeRefused, nothing sent
        job = _JobSpec(on_progress, timeout, observer or JobObserver(), log, abort, resume)
        result = self._submit(snapshot, from_line, job, wait=True, from_arm=False, stops=stops)
        assert result is not None
        return result

    def wait(self) -> None:
        """Return when every move queued with ``wait=False`` has run (its error, if one failed)."""
        self._call(lambda: None)

    # --- reading and control -----------------------------------------------------------------

    def status(self, timeout: float | None = None) -> ArmStatus:
        """The arm's decoded report, once every status kind has been seen (after the moves and
        the job asked for before it ran); ``JobFailed`` when it is not complete within
        ``timeout`` seconds (default ``status_timeout_s``)."""
        timeout_s = self.status_timeout_s if timeout is None else _check_timeout(timeout, "STATUS_TIMEOUT_RANGE_S")

        def read() -> ArmStatus:
            state, now = self._complete_state(timeout_s), self._link.clock()

            def age(kinds) -> float | None:
                seen = [state.last_seen[k] for k in kinds if k in state.last_seen]
                return now - min(seen) if seen else None

            return ArmStatus(position_mm=state.position_mm, joints_deg=tuple(state.joints_deg),
                             worktable_mm=tuple(state.worktable_mm), wrist_deg=(state.w0_deg, state.w1_deg),
                             pwm_us=state.pwm_us, paused=state.paused, run_position=state.run_position,
                             ages_s={name: age(kinds) for name, kinds in _AGE_KINDS.items()})

        return self._call(read)

    def status_json(self, timeout: float | None = None, *, at_once: bool = False) -> dict:
        """The arm's decoded report with the keys of ``armctl status --once --json``, once every
        status kind has been seen (``JobFailed`` otherwise, within ``timeout`` seconds).  After
        everything queued on the worker — or, ``at_once``, read from the link's reader thread now,
        even while a job runs (a wall-clock port only: on a virtual clock model time moves only on
        the worker, so there it waits its turn all the same)."""
        timeout_s = self.status_timeout_s if timeout is None else _check_timeout(timeout, "STATUS_TIMEOUT_RANGE_S")

        def read() -> dict:
            return self._complete_state(timeout_s).to_json()

        return read() if at_once and not self.is_virtual else self._call(read)

    def _complete_state(self, timeout_s: float):
        """A copy of the link's state once every status kind has been seen (``JobFailed`` after
        ``timeout_s``): what ``status`` and ``status_json`` read."""
        link = self._link
        if not link.wait_until(lambda s: s.complete, timeout_s):
            raise JobFailed(f"no complete status from {link.url} within {timeout_s:g} s")
        return link.snapshot()[0]

    def pause(self) -> bool:
        """Pause the arm.  During a job (``run``, or a ``move`` with ``wait=False``) this asks
        the job engine, as the run panel's key does: the protocol's pause toggle, and no frame
        written until ``resume`` (in the ``queued`` control mode, H5, the arm pauses after the
        frames already queued).  On an idle arm the toggle is sent only when two agreeing
        reports say it runs (armctl/job_control.py's pause rule: a toggle on a guess could
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
        answer = self._ask_job(lambda job: job.resume() or job.pause())
        if answer is _JOB_ENDED:
            raise ArmctlError(f"no job is running on {self.url}: nothing to pause")
        return answer

    def feed_override(self, percent: float, *, relative: bool = False) -> int:
        """Rescale the speed of the running job's frames not yet written, as the run panel's
        −/+ keys do: ``percent`` of the script's speeds, put on the engine's grid (10…200 %,
        in steps of 10: armctl/feed.py) and never past the profile's limits; the effect shows
        within the lead.  Returns the percentage in force.  The override lasts for this job
        only; ``ArmctlError`` when no job is running.  ``relative=True``: ``percent`` is added
        to the percentage in force, in the engine's turn (the panel's −/+ keys: ∓10)."""
        if isinstance(percent, bool) or not isinstance(percent, numbers.Real):
            raise TypeError(f"feed_override(): percent must be a number, not {_short(percent)}")
        low, high = FEED_OVERRIDE_RANGE_PERCENT
        try:  # here, not in the job: a number the engine cannot take must not end the job "failed"
            value = float(percent)
        except OverflowError:
            value = math.inf
        if not low <= value <= high:  # NaN, ±inf and 10**60 too
            raise ValueError(f"feed_override(): percent={_short(percent)} must be a number from {low:g} to {high:g} "
                             "(it is then put on the 10…200 % grid)")
        answer = self._ask_job(lambda job: job.set_feed_override(value + (job.control.feed.percent if relative else 0)))
        if answer is _JOB_ENDED:
            raise ArmctlError(f"no job is running on {self.url}: there is no feed to override")
        return answer

    def stop(self, why: str | None = None) -> None:
        """Stop as ``armctl run``'s Ctrl-C does: cancel the queued moves, stop feeding the running
        job, send the abort sequence (a pause toggle, not sent to an arm that reports it is
        paused) and wait for the arm; the job's ``run`` returns outcome "interrupted".  The next
        job resumes an arm left paused.  Nothing to stop: does nothing.  A job being read or
        planned when it comes sends nothing (outcome "interrupted").  ``why``: a note the
        result's ``messages`` carry (``armctl run``: "stopped by SIGTERM").  Called again while
        the job stops: the wait for the arm to come to rest is cut short (a second Ctrl-C)."""
        with self._lock:
            self._stops += 1
            queued, self._queued = self._queued, []
            job = self._job
        for future in queued:  # outside the lock: cancel() calls _queued_done at once
            future.cancel()
        if job is not None:
            job.request_stop(why)

    # --- the worker --------------------------------------------------------------------------

    def _ask_job(self, action: Callable[[Any], Any]) -> Any:
        """``action(job)`` carried out by the running job's engine at the runner's next turn
        (at once when called on the worker, from ``on_progress``: that is between two turns);
        ``_JOB_ENDED`` when no job is running or it ended first."""
        with self._lock:
            job = self._job if self._job is not None and not self._job.stop_asked else None
            if job is None:
                return _JOB_ENDED
            if self._worker.is_current():
                return action(job.runner.job)
            future = job.request(action)
        return future.result()

    def _set_paused(self, want_paused: bool) -> bool:
        answer = self._ask_job((lambda job: job.pause()) if want_paused else (lambda job: job.resume()))
        if answer is not _JOB_ENDED:
            return answer
        # no job running, or it ended before carrying the request out: ask the idle arm

        def idle_toggle() -> bool:
            from .job_control import pause_toggle_needed
            from .jobflow import reported_pause

            link = self._link
            sent = pause_toggle_needed(want_paused, reported_pause(link, PAUSE_READ_TIMEOUT_S))
            if sent:
                _write_toggle(link)
            if sent is None:
                raise JobFailed("the arm's pause reports did not agree twice in a row: no pause toggle sent")
            if sent and not link.wait_until(lambda s: s.paused is want_paused, PAUSE_READ_TIMEOUT_S):
                raise JobFailed(f"the arm did not report it {'paused' if want_paused else 'resumed'} after a pause toggle")
            return sent

        return self._call(idle_toggle)

    def _call(self, task: Callable[[], Any]) -> Any:
        """Run ``task`` on the worker after everything queued — unless a queued move failed:
        then its error is raised and ``task`` does not run."""
        if self._closed:
            raise ArmctlError(f"the arm on {self.url} is closed")

        def unless_failed():
            return _SKIPPED if self._deferred is not None else task()

        try:
            result = self._worker.call(unless_failed)
        finally:
            self._raise_deferred()
        if result is _SKIPPED:  # another thread took the queued move's error first
            raise JobFailed("not run: a move queued before it failed")
        return result

    def _raise_deferred(self) -> None:
        with self._lock:
            error, self._deferred = self._deferred, None
        if error is not None:
            raise error

    def _submit(self, script, from_line: int, spec: _JobSpec, wait: bool, from_arm: bool,
                stops: int | None = None) -> RunResult | None:
        """Check ``script`` here (``ScriptError``, nothing sent), then run it on the worker.

        ``from_arm``: the script is a move's one line, whose words left out are the arm's; it
        is checked here from the profile's fixed pose (so a bad word fails at once, even with
        ``wait=False``), and again on the worker from the arm's report before it is sent.  A
        job (``run``) is checked as ``armctl run`` checks it: from nothing known.  ``stops``: the
        count of ``stop()`` calls when the call began (default: now) — one since then, during the
        check, ends the job with nothing sent, as one while the arm is read does."""
        from .jobflow import from_line_errors, start_at

        stops = self._stops if stops is None else stops

        _check_timeout(spec.timeout_s)

        _check(script, self._profile, start_at(self._model)[1] if from_arm else None)
        error = from_line_errors(script, from_line)
        if error is not None:
            raise error

        def job() -> RunResult:
            return self._run_job(script, from_line, spec, from_arm, stops)

        if wait:
            return self._call(job)
        if self._closed:
            raise ArmctlError(f"the arm on {self.url} is closed")

        def queued() -> RunResult | None:
            if stops != self._stops:
                return None  # stop() came after this move was queued (it cancels the queue)
            if self._deferred is not None:
                raise JobFailed("not sent: a move queued before it failed")
            return job()

        with self._lock:
            future = self._worker.submit(queued)
            self._queued.append(future)
        future.add_done_callback(self._queued_done)
        return None

    def _queued_done(self, future: Future) -> None:
        """A queued move ended (on the worker): keep its error; a failure cancels the rest."""
        error = None if future.cancelled() else future.exception()
        with self._lock:
            if future in self._queued:
                self._queued.remove(future)
            if error is None:
                return
            self._deferred = self._deferred or error
            later, self._queued = self._queued, []
        for queued in later:  # outside the lock: cancel() calls this method again at once
            queued.cancel()

    def _run_job(self, script, from_line: int, spec: _JobSpec, from_arm: bool, stops: int) -> RunResult:
        """On the worker: read the arm, plan from its report, drive the runner, report.  A
        ``stop()`` that came after the call and before the first frame ends it with nothing sent."""
        from .jobflow import (JournalFile, drive, from_line_errors, journal_for, plan_job, read_arm, resume_paused,
                              resume_start, start_from_state, start_job)
        from .joblog import job_record, target_of
        from .calibration import stale_notes
        from .runner import abort_frames

        link, observer = self._link, spec.observer
        arrival = self._profile.connector.control_on_arrival
        journal = None if spec.log is None else JournalFile(spec.log, sync=not getattr(link.clock, "virtual", False))
        # a resume decides from the arm as it is, paused or not: it continues or refuses before it sends anything
        state = read_arm(link, self.status_timeout_s, journal, note=observer.note, control_on_arrival=arrival,
                         unpause=spec.resume is None)
        if spec.resume is not None:
            for told in spec.resume.notes:  # e.g. the torn last line a crash left, ignored
                observer.note(f"armctl: --resume: {told}")
            started = resume_start(link, spec.resume, self.status_timeout_s, self.lead_s,
                                   stopped=lambda: stops != self._stops)
            if started is None:  # stop() (Ctrl-C) while the arm ran out its queue: no frame goes
                return RunResult.nothing_sent("interrupted")
            state, from_line = started
            if from_line is None:
                return RunResult.nothing_sent("finished", message="nothing to resume: every line of the job is proven executed")
            error = from_line_errors(script, from_line)
            if error is not None:
                raise error
            observer.note(f"armctl: resuming {script.name} at line {from_line}: the log and the arm's report prove every line "
                          "before it ran")
            resume_paused(link, self.status_timeout_s, journal, observer.note, arrival)
            state = link.snapshot()[0]
        report = _check(script, self._profile, start_from_state(self._model, state)[1] if from_arm else None)
        for diagnostic in report.diagnostics:  # for people, not the result (armctl run prints its own, before)
            if diagnostic.severity != "error":
                observer.warning(diagnostic)
        plan = plan_job(script, self._model, state, self.lead_s, self._baud, from_line)
        if plan.estimate.frames == 0:
            where = f" from line {from_line}" if from_line > 1 else ""
            return RunResult.nothing_sent("finished", message=f"nothing to send: the script has no frames{where}")
        if stops != self._stops:  # stop() (Ctrl-C) while the arm was read: no frame goes
            return RunResult.nothing_sent("interrupted")
        runner = start_job(link, script, self._model, plan, self.lead_s, self._baud, report.lines, journal)
        if journal is not None:  # which script it records (resume= checks it); a failed write stops the job like any
            known = state.position_mm is not None and None not in state.joints_deg
            start = target_of("line", state.position_mm, state.joints_deg) if known else None
            runner.log_record(job_record(script.name, script.data, from_line, self.lead_s, plan.estimate.frames, arrival,
                                         start), durable=True)
        control = _JobControl(runner, spec.on_progress, spec.timeout_s, observer, journal_for(runner, script, journal))
        runner.on_update = control.on_update
        link.on_status = runner.on_status
        with self._lock:
            self._job = control
            stopped = stops != self._stops  # a stop() between the check above and here
        try:
            if stopped:
                control.request_stop()
            observer.started(runner.view, plan)
            outcome = drive(runner, abort_frames(spec.abort, arrival), on_stopping=lambda why: observer.note(
                f"\narmctl: {why}: no more frames are sent; sending the abort sequence ({spec.abort}) and waiting for "
                "the arm to come to rest …"))
        finally:
            with self._lock:
                self._job = None
                control.end()
            link.on_status = None
        runner.view.messages.extend(stale_notes(self._profile, link.url, runner.streamer.slowest_proven,
                                                outcome == "frames may have been lost"))
        result = RunResult.of(runner.view, outcome, script.lines(), estimated_job_s=plan.estimate.job_s)
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
