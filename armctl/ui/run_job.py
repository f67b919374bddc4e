"""``armctl run`` and ``armctl estimate``: check, then a client of the Python API; report.

Strategy: ``armctl run`` is the Python API (``armctl.Arm``, armctl/host/api.py) plus presentation.
It checks the whole script first (``checked.check``), printing every finding (nothing is opened
before it passes), then ``Arm.open`` and ``Arm.run`` — handed that ``CheckedScript``, which they
do not check again — do the job — read the arm, plan, stream through the one job
engine, end it, journal it to ``--log``, resume from a log — and this module only shows it: the
live panel or plain progress lines or ``--json`` events (a ``JobObserver``), notes on stderr
above the panel, the panel's keys and Ctrl-C as calls on the arm (``toggle_pause``,
``feed_override``, ``stop``), the summary, and the exit code the ``RunResult`` carries.

What was checked is exactly what is sent: the script is read once, before anything else, into
an immutable ``ScriptSnapshot`` (armctl/script/files.py), and every step — the lint check, the
``--from-line`` check, the estimate, the stream and the resume line of the summary — compiles
that same snapshot, never the file again (``Arm.run`` takes the checked snapshot itself).  Compiling is
deterministic, so an edit to the file while the job streams changes nothing that is sent;
stdin (``run -``) works the same way.

Any failure mid-job — Ctrl-C, a ``--log`` that cannot be written, an unexpected error — takes
the API's one path (``jobflow.drive``): stop feeding, send the abort sequence, wait for the
arm; then the summary says the last line sent, the last line known executed and the resume line.
"""
from __future__ import annotations

import sys
import time
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass

import click

from ..errors import ArmctlError, ScriptError
from ..errors import EXIT_INTERRUPTED, EXIT_OK, EXIT_PROBLEMS, UsageFailure, exit_code_for
from ..host.jobflow import WAIT_CUT_SHORT, JobFailed
from ..host.log_lock import locked
from ..core.job_end import PROBE_HINT
from ..core.protocol import describe
from ..core.streamer import DEFAULT_LEAD_S

LIVE_REFRESH_S = 0.25  # the panel is drawn at most 4 times a second (ui/live_lines.py: only the lines that changed)
PLAIN_PROGRESS_S = 2.0
# The least terminal the panel's map is drawn in: its ~24 rows with the map, a few lines of
# notes above; the map's rows are 60 columns with their label.
MAP_MIN_WIDTH, MAP_MIN_HEIGHT = 80, 30


@dataclass
class JobOptions:
    script: str
    port: str | None
    baud: int | None
    lead_s: float
    from_line: int
    dry_run: bool
    log_path: str | None
    live: bool
    abort: str
    profile_path: str | None
    timeout_s: float
    json: bool = False  # --json: JSON lines on stdout (ui/run_json.py), everything else on stderr
    resume_log: str | None = None  # --resume LOG: continue the job that LOG records
    other_port: bool = False  # --other-port: --port is the arm LOG's job ran on, moved to another port


def check_script(script, profile, from_line: int = 1):
    """The same checks as ``armctl lint`` over the whole script (a ``ScriptSnapshot``) before
    anything is sent, and then whether ``from_line`` can start it: any error prints every finding
    and exits 1; warnings are shown and the job goes on.  The ``CheckedScript``, for ``Arm.run``."""
    from ..core.checked import check
    from .output import quiet

    checked = check(script, profile, from_line=from_line)
    report = checked.report
    shown = [d for d in report.diagnostics if d.severity == "error"] if quiet() else report.diagnostics  # -q: no warnings
    _refuse_on_errors(shown, report.errors)
    if checked.from_line_error is not None:  # a resume line the compiler cannot start at (inside an arc, a block, past the end)
        _refuse_on_errors(checked.from_line_error.diagnostics, checked.from_line_error.errors)
    return checked


class ScriptRefused(SystemExit):
    """Exit 1: the script has errors (printed on stderr); ``run --json`` reports ``diagnostics``."""

    def __init__(self, diagnostics) -> None:
        super().__init__(EXIT_PROBLEMS)
        self.diagnostics = list(diagnostics)


def _refuse_on_errors(diagnostics, errors: int) -> None:
    for diagnostic in diagnostics:
        click.echo(diagnostic.render(), err=True)
    if errors:
        click.echo(f"{errors} error{'s' if errors != 1 else ''}: nothing was sent to the arm", err=True)
        raise ScriptRefused([d for d in diagnostics if d.severity == "error"])


def plan_job(checked, model, lead_s: float, baud: int):
    """``checked`` planned from the profile's fixed pose 0 (a ``CheckedJob``); a job whose motion
    time passes ``MAX_JOB_MOTION_S`` is refused (E012 at the line where it does; exit 1)."""
    from ..core.checked import plan

    try:
        return plan(checked, model, model.initial_pose(), None, lead_s, baud)
    except ScriptError as error:
        _refuse_on_errors(error.diagnostics, error.errors)


def print_estimate(result, header: str) -> None:
    click.echo(header)
    click.echo(f"  frames            {result.frames}")
    click.echo(f"  job time          {result.job_s:.1f} s (motion {result.motion_s:.1f} s)")
    click.echo(f"  line-bound share  {result.line_bound_share:.1%} (the arm waiting for the serial line)")
    click.echo(f"  arm-bound share   {1 - result.line_bound_share:.1%}")
    click.echo(f"  path              {result.path_mm:.1f} mm Cartesian, {result.joint_path_deg:.1f} deg of joint moves")
    click.echo(f"  peak queue        {result.peak_queue_frames} frames, {result.peak_queue_s:.1f} s of motion")
    for note in result.notes:
        click.echo(f"  note: {note}")


def dry_run(options: JobOptions, checked, model, port=None) -> int:
    """The frames and the estimate, no port opened (``port``: the one named, its arm read once)."""
    # the estimate first: it refuses a job too long to run (E012) before a frame is printed
    job = plan_job(checked, model, options.lead_s, options.baud or configured_baud(port))
    for statement in job.statements():
        frame = statement.command.encode()
        click.echo(f"{statement.line:>6}  {frame.hex()}  {describe(statement.command)}")
    print_estimate(job.estimate, "dry run: no port opened; estimate from the profile's fixed pose 0:")
    return EXIT_OK


def configured_baud(port=None) -> int:
    """The line rate ``run`` opens ``port`` (a URL or a ``PortChoice``) at without ``--baud`` (None:
    the configured port), and
    what ``--dry-run`` and ``estimate`` plan with: armctl.toml's (the project's, else yours), else
    what ``armctl probe`` read the arm there at, else 9600 (``link.line_baud``); a port it cannot
    name does not stop it (``calibration.quiet_port``)."""
    from ..host.calibration import quiet_port
    from ..host.link import line_baud
    from ..host.profile import load_config

    config = load_config()
    return line_baud(None, config, quiet_port(port, config))[0]


def _same_file(first: str, second: str) -> bool:
    """Two names of one file (a link, another spelling), or of one that does not exist yet."""
    import os

    try:
        return os.path.samefile(first, second)
    except OSError:
        return os.path.realpath(first) == os.path.realpath(second)


def _open_log(path: str):
    """The --log file, line-buffered: a write failure (disk full) shows at the line that failed.
    One that cannot be opened is a usage error (exit 2, and with --json its summary object).
    A regular file is locked for this run before it is emptied: a second run given the same
    --log while one writes it would otherwise truncate that job's journal under it (its resume
    then refused as damaged) — it is refused instead, exit 2, before the arm is touched."""
    import os
    import stat

    try:
        log = open(path, "a", encoding="utf-8", buffering=1)  # emptied below, once it is this run's
        regular = stat.S_ISREG(os.fstat(log.fileno()).st_mode)
    except OSError as error:
        raise UsageFailure(f"cannot write --log {path}: {error.strerror or error}") from None
    try:
        if regular and not locked(log):
            raise UsageFailure(f"--log {path} is the journal of a job another armctl is running: it is not "
                               "written over; give this job a --log of its own")
        if regular:
            log.truncate(0)
    except OSError as error:
        log.close()
        raise UsageFailure(f"cannot write --log {path}: {error.strerror or error}") from None
    except UsageFailure:
        log.close()
        raise
    return log


@contextmanager
def _log_file(path: str):
    """``_open_log``, closed at the end; a close that fails again after a failed write (the
    line still buffered) is not a second error: the job already stopped on the first."""
    log = _open_log(path)
    try:
        yield log
    finally:
        try:
            log.close()
        except OSError:
            pass


def run_job(options: JobOptions, script, connect) -> int:
    """Run the job in ``script`` (the ``ScriptSnapshot`` read once; ``options.script`` is only
    the name the summary shows); ``connect`` opens the port (``Arm.open``'s ``connect``)."""
    if options.json:
        return _run_json(options, script, connect)
    return _run_job(options, script, connect)


def _run_json(options: JobOptions, script, connect) -> int:
    """``--json``: the events and the one summary on stdout; what the run prints for people
    (the banner, the summary's text, notes) goes to stderr."""
    from contextlib import redirect_stdout
    from dataclasses import replace

    from .run_json import JsonEvents, failure_result

    events = JsonEvents(sys.stdout)
    with redirect_stdout(sys.stderr):
        try:
            code = _run_job(replace(options, live=False), script, connect, events)
            if events.reader_gone:  # the job stopped cleanly for it; the exit is the broken pipe's (141)
                raise BrokenPipeError("the program reading --json went away")
            return code
        except ScriptRefused as refused:
            events.summary(failure_result("refused", refused.code, diagnostics=refused.diagnostics))
            raise
        except ArmctlError as error:
            events.summary(failure_result("failed", exit_code_for(error), message=str(error)))
            raise
        except KeyboardInterrupt:
            events.summary(failure_result("interrupted", EXIT_INTERRUPTED))
            raise


def refuse_with_dry_run(as_json: bool, resume_log) -> None:
    """The options a dry run cannot honour, each a usage error before the script is read."""
    if as_json:
        raise UsageFailure("--json with --dry-run: `armctl compile --json` gives the frames, `armctl estimate --json` the estimate")
    if resume_log is not None:  # the line to continue at is the arm's report's, and a dry run opens no port
        raise UsageFailure("--resume with --dry-run: the line to continue at needs the arm's report, and a dry run "
                           "opens no port (`armctl run JOB --dry-run --from-line N` shows what a resume at N sends)")


def _run_job(options: JobOptions, script, connect, events=None) -> int:
    """Check (printing every finding), then the job through the Python API: ``Arm.open`` and
    ``Arm.run``; this keeps the presentation — the panel or the JSON events, the notes, the
    keys and Ctrl-C as calls on the arm, the summary and the exit code."""
    from dataclasses import replace

    from ..host.api import Arm
    from ..host.results import RunResult
    from ..host.jobflow import read_resume_point
    from ..host.log_lock import resume_claim
    from ..host.link import choose_port
    from ..host.resume_port import resume_port
    from ..host.resume_words import CLI
    from ..host.calibration import arm_profile, quiet_port, with_arm
    from ..core.motion import MotionModel

    if options.other_port and not options.resume_log:
        raise UsageFailure("--other-port is for --resume LOG: it says --port is the arm LOG's job ran on")
    # read first (before --log is opened for writing, and before the port): its port is the one to open
    resume = read_resume_point(options.resume_log, script, options.from_line, CLI) if options.resume_log else None
    if resume is not None:  # the arm the log's job ran on (refused: another arm's --port)
        port, told, resume = resume_port(resume, options.port, options.other_port)
        port = with_arm(port)  # (read already where the resume checked the arm)
        options = replace(options, port=port.url)  # (the resume command a stop prints names that arm)
        if told is not None:
            click.echo(f"armctl: {told}", err=True)
    else:  # the arm on the port read once: the profile carries its stored calibration (a dry run
        # opens none: the port given, else the configured one, as estimate: None if it names no arm)
        port = with_arm(choose_port(options.port)) if not options.dry_run else \
            quiet_port(None) if options.port is None else with_arm(options.port)
    profile = arm_profile(options.profile_path, port=port)
    checked = check_script(script, profile, options.from_line)
    if options.dry_run:
        return dry_run(options, checked, MotionModel(profile), port)
    if options.resume_log and options.log_path and _same_file(options.resume_log, options.log_path):
        raise UsageFailure(f"--log {options.log_path} is the journal --resume reads: it is never written over; "
                           "give the resumed job a --log of its own")
    watch = _RunObserver(options, MotionModel(profile), events)
    # the log before the port: one that cannot be written refuses the job before the arm is touched
    with (resume_claim(options.resume_log) if options.resume_log else nullcontext()), \
            (_log_file(options.log_path) if options.log_path else nullcontext()) as log, \
            Arm.open(port, options.baud, profile, lead_s=options.lead_s, status_timeout_s=options.timeout_s,
                     connect=connect) as arm:
        if events is not None:  # `| head -1`: the reader went away — the job stops as Ctrl-C stops it
            events.on_reader_gone = lambda: arm.stop("the program reading --json went away")
        with _stop_signals(arm, watch), (_keys(arm) if watch.keys else nullcontext()):
            try:
                result = arm.run(checked, from_line=options.from_line, observer=watch, log=log, abort=options.abort,
                                 resume=resume)
            except ScriptError as error:  # the script cannot run from where the arm is: nothing was sent
                _refuse_on_errors(error.diagnostics, error.errors)
            except JobFailed as error:
                if error.result is None:
                    raise
                result = error.result
            except KeyboardInterrupt:  # Ctrl-C before the first frame (``_stop_signals``): nothing sent, of the job's
                # frames (a resume's first line is the arm's report's to decide: its total is not known yet)
                if events is not None and watch.view is None:
                    events.summary(RunResult.interrupted_before_start(checked if resume is None else None).to_json())
                raise
            finally:
                watch.display.__exit__(None, None, None)
        return _report(result, watch, options, events)  # before the port and the log close, as the job's end


def _report(result, watch, options: JobOptions, events) -> int:
    """The summary (text, and with --json the summary object); the exit code."""
    if watch.view is None:  # no frame was sent
        if result.outcome == "interrupted":
            raise KeyboardInterrupt  # Ctrl-C before the job started: as any Ctrl-C outside a job
        for message in result.messages:
            click.echo(message)
        if events is not None:
            events.summary(result.to_json())
        return result.exit_code
    from dataclasses import replace

    wall_s = time.monotonic() - watch.wall_start
    if result.resume_line is not None:
        result = replace(result, resume_command=resume_command(options, result.resume_line))
    code = _summary(result, watch.view, wall_s, watch.estimate, options, watch.departures.explanation())
    if events is not None:
        events.summary(result.to_json())
    return code


class Departures:
    """What a job did that its estimate does not assume, followed turn by turn: the arm's-clock
    seconds it was paused (or pausing/resuming), and the feed overrides in force."""

    def __init__(self) -> None:
        self.paused_s = 0.0
        self.feed_percents: set[int] = set()
        self._last: tuple[float, str] | None = None

    def update(self, view) -> None:
        now_s, state = view.now_s, getattr(view, "pause_state", "running")
        if self._last is not None and self._last[1] != "running":
            self.paused_s += max(0.0, now_s - self._last[0])
        self._last = (now_s, state)
        percent = getattr(view, "feed_percent", 100)
        if percent != 100:
            self.feed_percents.add(percent)

    def explanation(self) -> str:
        """``the estimate assumes no pause and 100 % feed: this job was paused 8.0 s and ran at
        120 % feed for part of it, which explains the difference`` — or "" when it did neither."""
        done = []
        if self.paused_s >= 0.05:
            done.append(f"was paused {self.paused_s:.1f} s")
        if self.feed_percents:
            percents = "/".join(f"{p} %" for p in sorted(self.feed_percents))
            done.append(f"ran at {percents} feed for part of it")
        if not done:
            return ""
        return ("the estimate assumes no pause and 100 % feed: this job " + " and ".join(done)
                + f", which {'explain' if len(done) > 1 else 'explains'} the difference")


class _RunObserver:
    """``armctl run``'s ``JobObserver`` (duck-typed: the API's import stays lazy): the live panel,
    the plain progress lines or the --json events, and the notes on stderr above the panel."""

    def __init__(self, options: JobOptions, model, events) -> None:
        from .output import quiet
        from .run_keys import FOOTER, keys_available

        self.options, self.model, self.events = options, model, events
        self.keys = _live(options) and keys_available()
        self.display = _Display(f"armctl run {options.script}", _live(options), footer=FOOTER if self.keys else None)
        self.quiet = quiet()
        self.view = None  # the job's RunView, once started
        self.wall_start = time.monotonic()
        self.departures = Departures()  # pauses and feed overrides: what the estimate did not assume

    def started(self, view, plan) -> None:
        self.view, self.estimate, self.wall_start = view, plan.estimate, time.monotonic()
        if self.display.live:  # the panel's map: the job compiled as it is sent, sampled once before the first frame
            self.display.grid = _job_grid(plan, self.model)
        self.display.__enter__()
        if self.events is not None:
            self.events.started(view, self.options.script, plan.from_line)

    def update(self, view) -> None:
        self.departures.update(view)
        if self.events is not None:
            self.events.update(view)
        elif not self.quiet:  # -q: the summary only
            self.display.update(view)

    def note(self, text: str) -> None:
        self.display.note(text)

    def warning(self, diagnostic) -> None:
        pass  # check_script printed the script's warnings before the port was opened


def _stop_signals(arm, watch):
    """Ctrl-C (or SIGTERM, SIGHUP: armctl/host/stop_signals.py) is ``arm.stop()``: the job stops at
    its next safe point (between writes), sends the abort sequence and waits for the arm; a
    second one cuts the wait short.  Before the first frame, any of the three stops at once, as
    outside a job: ``arm.stop()`` alone would be lost while ``arm.run`` is still checking the
    script (the API counts a stop from when it registers the job), and the job would run to its end."""
    import signal

    from ..host.stop_signals import stop_signals

    def on_stop(signum: int) -> None:
        why = None if signum == signal.SIGINT else f"stopped by {signal.Signals(signum).name}"
        if watch.view is None:
            arm.stop(why)  # the arm is being read: nothing will be sent
            raise KeyboardInterrupt
        arm.stop(why)

    return stop_signals(on_stop)


def _keys(arm):
    from .run_keys import run_keys

    return run_keys(arm)


def _live(options: JobOptions) -> bool:
    """The rich panel, rather than plain progress lines: asked for, stdout is a terminal, not -q."""
    from .output import quiet

    return options.live and sys.stdout.isatty() and not quiet()


def _job_grid(job, model):
    from .path_map import job_grid

    return job_grid(job.statements(), model, job.start)


class _Display:
    """A live panel on a terminal (ui/live_lines.py: the lines that changed, at most every
    ``LIVE_REFRESH_S``), plain progress lines elsewhere; throttled.

    While the panel is live it owns the screen: it is redrawn by moving the cursor up over
    the lines drawn last, so a line written past it (a raw write to stderr) makes the next
    redraw land too low and leaves a stray partial panel above the real one.  Every message
    printed during the job therefore goes through ``note``, which prints it above the panel.

    The job's map (``grid``, a path_map.PathGrid, or None) is drawn while the terminal has room
    for it (MAP_MIN_WIDTH × MAP_MIN_HEIGHT, checked at every redraw, so a resize counts); the
    lines of a panel taller than the screen would be cut.
    """

    def __init__(self, title: str, live: bool, console=None, grid=None, footer: str | None = None) -> None:
        self.title, self.live, self.grid, self.footer = title, live, grid, footer
        self._console = console  # tests pass a recording console; None: rich's own (stdout)
        self._live = None
        self._last = 0.0

    def __enter__(self):
        if self.live:
            from rich.console import Console

            from .live_lines import LiveLines

            from rich.text import Text

            self._live = LiveLines(self._console or Console()).__enter__()
            self._live.draw(Text("starting …"))
        return self

    def __exit__(self, *exc):
        if self._live is not None:
            live, self._live = self._live, None
            live.__exit__(*exc)

    def note(self, text: str) -> None:
        """A message for stderr that the live panel must not be broken by."""
        if self._live is not None and sys.stderr.isatty():
            from rich.text import Text

            # printed where the panel begins, the panel drawn again below it; the leading
            # newline that moves past an echoed ^C on a plain terminal is not needed here
            self._live.print_above(Text(text.lstrip("\n")))
        else:
            click.echo(text, err=True)

    def update(self, view) -> None:
        now = time.monotonic()
        if self._live is not None:
            if now - self._last >= LIVE_REFRESH_S or view.outcome != "running":
                from .run_panel import render_run

                self._live.draw(render_run(view, self.title, self._map_room(), self.footer))  # the lines that changed
                self._last = now
        elif now - self._last >= PLAIN_PROGRESS_S:
            from .run_panel import progress_line

            click.echo(progress_line(view))
            self._last = now

    def _map_room(self):
        """The grid if the terminal has room for the panel with it, else None."""
        if self.grid is None:
            return None
        width, height = self._live.console.size
        return self.grid if width >= MAP_MIN_WIDTH and height >= MAP_MIN_HEIGHT else None


def resume_command(options: JobOptions, line: int) -> str:
    """The command that continues this job on the same arm: every option that shaped the run
    (port, baud, lead, profile, abort), quoted for a POSIX shell.  Without them a resume could
    reach another port, or check the script against the illustrative profile instead of yours.
    A port, baud or profile that came from armctl.toml or ARMCTL_PORT is left to come from there."""
    import shlex

    words = ["armctl", "run", options.script, "--from-line", str(line)]
    if options.port is not None:
        words += ["--port", options.port]
    if options.baud is not None:
        words += ["--baud", str(options.baud)]
    if options.lead_s != DEFAULT_LEAD_S:
        words += ["--lead", f"{options.lead_s:g}"]
    if options.profile_path is not None:
        words += ["--profile", options.profile_path]
    if options.abort != "pause":
        words += ["--abort", options.abort]
    return shlex.join(words)


def one_line_summary(result, position_mm) -> str:
    """What ``armctl move``/``home`` print: the outcome, the arm time and (finished) where the
    arm reports it is at rest."""
    time_s = "" if result.arm_time_s is None else f" in {result.arm_time_s:.1f} s of arm time"
    where = "" if position_mm is None else " at X{:z.1f} Y{:z.1f} Z{:z.1f}".format(*position_mm)
    if result.finished:
        return f"finished: the arm is at rest{where}{time_s}"
    messages = "".join(f"; {message}" for message in result.messages)
    return f"{result.outcome}{time_s}{messages}"


def _repeat_note(view, resume: int | None) -> str:
    """What the summary says when the resume line is a repeat block's start (jobflow.resume_line:
    --from-line cannot start inside one): the passes already done run again."""
    loop = getattr(view.first_not_done, "loop", ()) if resume is not None else ()
    if not loop:
        return ""
    return (f" (line {view.resume_line()} is inside a repeat block, in pass {loop[-1] + 1}: the block "
            "runs again from its first pass, so the passes already done are repeated)")


def _summary(result, view, wall_s: float, estimate, options: JobOptions, departures: str = "") -> int:
    """The text summary of ``result`` (the arm time unrounded, from ``view``); the exit code.
    ``departures``: what explains the difference from the estimate (``Departures``)."""
    click.echo(f"frames: {result.frames_sent} of {result.total_frames} sent")
    click.echo(f"time: {wall_s:.1f} s wall")
    if view.arm_time_s is not None:
        actual = view.arm_time_s
        click.echo(f"arm time: {actual:.1f} s from the first frame to the arm at rest; estimated {estimate.job_s:.1f} s "
                   f"({actual / estimate.job_s - 1:+.1%})" if estimate.job_s else f"arm time: {actual:.1f} s")
        if departures:
            click.echo(f"  ({departures})")
    click.echo(f"frames confirmed by the arm's reports: {result.frames_by_reports}; by time only: {result.frames_by_time}"
               + (f"; gone from the buffer, not seen running: {result.frames_unseen}" if result.frames_unseen else ""))
    for message in result.messages:
        click.echo(f"note: {message}", err=True)
    if result.finished:
        click.echo("finished: the arm finished the job")
        return result.exit_code
    if result.outcome == "finished, unproven":
        if view.probe_answers:
            click.echo("finished, unproven: the arm is at rest at the last target, but what proves the job ran rests on "
                       f"settings not measured on this arm (the note above); {PROBE_HINT}")
        else:
            click.echo("finished, unproven: the arm is at rest at the last target, but its reports do not prove "
                       "every frame ran (the note above)")
        return result.exit_code
    sent, done = result.last_line_sent, result.last_line_executed
    click.echo(f"last line sent: {sent if sent is not None else 'none'}")
    click.echo(f"last line known executed: {done if done is not None else 'none'}")
    if result.resume_line is not None:
        click.echo(f"resume with: {result.resume_command}{_repeat_note(view, result.resume_line)}")
        if any(message.startswith(WAIT_CUT_SHORT) for message in result.messages):  # the arm may run on
            click.echo(f"  once the arm is at rest: it may have run lines from {result.resume_line} meanwhile, which that "
                       "runs again" + (f" (`--resume {options.log_path}` continues after the last that ran)"
                                       if options.log_path else ""))
    if result.outcome == "interrupted":
        click.echo("stopped: interrupted before the first frame" if result.frames_sent == 0 else
                   f"stopped: interrupted; abort sequence: {options.abort}", err=True)
    else:
        click.echo(f"stopped: {result.outcome}", err=True)
    return result.exit_code
