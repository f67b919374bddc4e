"""``armctl run`` and ``armctl estimate``: check, connect, stream, report.

Strategy: the sequence a careful operator would follow, each step a function — check the
whole script (nothing leaves before it passes), read the arm's state, estimate, stream with a
live view, and always end with a summary that says what ran and how to resume.  The pacing
itself is the pure Streamer's; the clock and the port are the runner's.

What was checked is exactly what is sent: the script is read once, before anything else, into
an immutable ``ScriptSnapshot`` (armctl/script/files.py), and every step — the lint check, the
``--from-line`` check, the estimate, the stream and the resume line of the summary — compiles
that same snapshot, never the file again.  Compiling is deterministic (the same lines and the
same initial state give the same frames), so an edit to the file or its replacement while the
job streams changes nothing that is sent; stdin (``run -``) works the same way.

Any failure mid-job — Ctrl-C, a ``--log`` that cannot be written, an unexpected error — takes
one path: stop feeding, send the abort sequence, wait for the arm, print the summary with the
last line sent, the last line known executed and the resume line.  Only a lost port skips
the abort (there is nothing to send it through).
"""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass

import click

from ..errors import ArmctlError, ScriptError
from ..jobflow import wait_for_rest
from ..jobflow import BlockIndex, outermost_block_start  # noqa: F401 - outermost_block_start re-exported (tests)
from ..protocol import describe
from ..streamer import DEFAULT_LEAD_S

EXIT_OK, EXIT_PROBLEMS, EXIT_INTERRUPTED = 0, 1, 130
LIVE_REFRESH_S = 0.1
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


def check_script(script, profile):
    """The same checks as ``armctl lint`` over the whole script (a ``ScriptSnapshot``) before
    anything is sent: any error prints every finding and exits 1; warnings are shown and the
    job goes on."""
    from ..output import quiet
    from ..jobflow import lint_script

    report = lint_script(script, profile)
    shown = [d for d in report.diagnostics if d.severity == "error"] if quiet() else report.diagnostics  # -q: no warnings
    _refuse_on_errors(shown, report.errors)
    return report


def check_from_line(script, from_line: int) -> None:
    """A resume line the compiler cannot start at (inside an arc, inside a repeat block, past
    the end) is an error like any other: nothing is sent."""
    from ..jobflow import from_line_errors

    error = from_line_errors(script, from_line)
    if error is not None:
        _refuse_on_errors(error.diagnostics, error.errors)


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


def estimate_job(script, model, start, lead_s, baud, from_line=1, initial=None):
    """The estimate of the job in ``script`` (a ``ScriptSnapshot``); a job whose motion time
    passes ``MAX_JOB_MOTION_S`` is refused (E012 at the line where it does; exit 1)."""
    from .. import jobflow

    try:
        return jobflow.estimate_job(script, model, start, lead_s, baud, from_line, initial)
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


def dry_run(options: JobOptions, script, model) -> int:
    start = model.initial_pose()
    # the estimate first: it refuses a job too long to run (E012) before a frame is printed
    result = estimate_job(script, model, start, options.lead_s, options.baud or _config_baud(), options.from_line)
    for statement in script.compile(from_line=options.from_line):
        frame = statement.command.encode()
        click.echo(f"{statement.line:>6}  {frame.hex()}  {describe(statement.command)}")
    print_estimate(result, "dry run: no port opened; estimate from the profile's fixed pose 0:")
    return EXIT_OK


def _config_baud() -> int:
    from ..link import config_baud
    from ..profile import load_config

    config = load_config()
    return config_baud(config.values, config.path_of("baud"))


def read_arm(link, timeout_s: float, log=None, control_on_arrival: bool = False):
    """jobflow.read_arm, telling on stderr when it resumes a paused arm."""
    from ..jobflow import read_arm

    return read_arm(link, timeout_s, log, note=lambda text: click.echo(text, err=True),
                    control_on_arrival=control_on_arrival)


def _open_log(path: str):
    """The --log file, line-buffered: a write failure (disk full) shows at the line that failed."""
    return open(path, "w", encoding="utf-8", buffering=1)


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
    the name the summary shows)."""
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
            return _run_job(replace(options, live=False), script, connect, events)
        except ScriptRefused as refused:
            events.summary(failure_result("refused", refused.code, diagnostics=refused.diagnostics))
            raise
        except ArmctlError as error:
            from ..cli import exit_code_for

            events.summary(failure_result("failed", exit_code_for(error), message=str(error)))
            raise
        except KeyboardInterrupt:
            events.summary(failure_result("interrupted", EXIT_INTERRUPTED))
            raise


def _run_job(options: JobOptions, script, connect, events=None) -> int:
    from ..motion import MotionModel
    from ..jobflow import plan_job, start_job
    from ..profile import load_profile

    profile = load_profile(options.profile_path)
    report = check_script(script, profile)
    check_from_line(script, options.from_line)
    model = MotionModel(profile)
    if options.dry_run:
        return dry_run(options, script, model)
    # A job too long to run (E012) was refused by check_script's lint, which judges the motion
    # time as estimate_job does; the estimate from the arm's own pose below judges it again over
    # the whole expansion, before anything is sent.  No third pass here.
    resume = _read_resume_log(options, script) if options.resume_log else None

    link, baud = connect(options.port, options.baud, profile=profile)
    with link, (_log_file(options.log_path) if options.log_path else nullcontext()) as log:
        state = read_arm(link, options.timeout_s, log, profile.connector.control_on_arrival)
        if resume is not None:
            state, options = _resume_from(resume, link, options, script)
            if options is None:
                click.echo("nothing to resume: every line of the job is proven executed")
                if events is not None:
                    events.summary(_nothing_to_run())
                return EXIT_OK
        try:
            plan = plan_job(script, model, state, options.lead_s, baud, options.from_line)
        except ScriptError as error:
            _refuse_on_errors(error.diagnostics, error.errors)
        estimate = plan.estimate
        if estimate.frames == 0:
            click.echo("nothing to send: the script has no frames" + (f" from line {options.from_line}" if options.from_line > 1 else ""))
            if events is not None:
                events.summary(_nothing_to_run())
            return EXIT_OK
        runner = start_job(link, script, model, plan, options.lead_s, baud, report.lines, log)
        view = runner.view
        if log is not None:  # which script it records (--resume checks it); a failed write stops the job like any
            from ..joblog import job_record

            runner.log_record(job_record(script.name, script.data, options.from_line, options.lead_s))
        # the live panel's map: the same snapshot compiled the same way, sampled once before the
        # first frame (bounded: path_map.MAP_MAX_FRAMES); no panel, no map
        grid = _job_grid(script, model, plan.start, plan.initial, options) if _live(options) else None
        link.on_status = runner.on_status
        wall_start = time.monotonic()
        if events is not None:
            events.started(view, options.script, options.from_line)
        outcome = _stream(runner, options, view, grid, events, _journal(runner, log, script))
        wall_s = time.monotonic() - wall_start
        result = job_result(view, outcome, options, script, estimate)
        code = _summary(result, view, wall_s, estimate, options)
        if events is not None:
            events.summary(result.to_json())
        return code


def _nothing_to_run() -> dict:
    from .run_json import failure_result

    return failure_result("finished", EXIT_OK)  # nothing was left to send: the job is done


def _read_resume_log(options: JobOptions, script):
    """The resume point LOG records for this very script (read before --log, which may be the
    same file, is opened for writing)."""
    from ..errors import ResumeRefused
    from ..joblog import read_resume_log

    if options.from_line != 1:
        raise ResumeRefused("--resume LOG decides the line to continue at: drop --from-line")
    from ..inputs import read_file_bounded

    try:  # bounded, as every input: an endless file (/dev/zero) is an error, not a hang
        text = read_file_bounded(options.resume_log, f"--resume {options.resume_log}").decode("utf-8", errors="replace")
        return read_resume_log(text.splitlines(), script.name, script.data)
    except ResumeRefused as error:
        raise ResumeRefused(f"--resume {options.resume_log}: {error}") from None
    except OSError as error:
        raise ResumeRefused(f"--resume {options.resume_log}: {error.strerror or error}") from None


def _resume_from(point, link, options: JobOptions, script):
    """Wait for the arm to come to rest (it runs out what was queued when the host died), then
    the line its report proves: (the state to start from, the options with that --from-line),
    or (state, None) when every line ran."""
    from dataclasses import replace

    from ..job import SETTLE_SLACK_S

    state = wait_for_rest(link, options.timeout_s + 2 * max(point.lead_s, options.lead_s) + SETTLE_SLACK_S)
    line = point.line_for(state.position_mm, tuple(state.joints_deg))
    if line is None:
        return state, None
    click.echo(f"armctl: resuming {options.script} at line {line}: the log and the arm's report prove every line before it ran",
               err=True)
    check_from_line(script, line)
    return state, replace(options, from_line=line)


def _journal(runner, log, script):
    """--log's progress records (armctl/joblog.py), or None without --log."""
    if log is None:
        return None
    from ..joblog import Journal

    blocks = BlockIndex(script.lines())

    def resume_at(statement) -> int:
        return (blocks.outermost_start(statement.line) or statement.line) if getattr(statement, "loop", ()) else statement.line

    journal = Journal(runner.log_record, resume_at)

    def update(view) -> None:
        pending = runner.streamer.pending
        journal.update(view, pending[-1].segment if pending else None)

    return update


def _stream(runner, options: JobOptions, view, grid=None, events=None, journal=None) -> str:
    from ..jobflow import drive
    from ..runner import abort_frames
    from .run_keys import FOOTER, keys_available, run_keys

    title = f"armctl run {options.script}"
    from ..output import quiet

    keys = _live(options) and keys_available()
    display = _Display(title, _live(options), grid=grid, footer=FOOTER if keys else None)
    shown = events.update if events is not None else (lambda view: None) if quiet() else display.update  # -q: the summary only
    runner.on_update = shown if journal is None else lambda view: (journal(view), shown(view))
    with _deferred_ctrl_c(runner), display, (run_keys(runner) if keys else nullcontext()):
        return drive(runner, abort_frames(options.abort, runner.streamer.control_on_arrival), on_stopping=lambda why: display.note(
            f"\narmctl: {why}: no more frames are sent; sending the abort sequence "
            f"({options.abort}) and waiting for the arm to come to rest …"))


def _live(options: JobOptions) -> bool:
    """The rich panel, rather than plain progress lines: asked for, stdout is a terminal, not -q."""
    from ..output import quiet

    return options.live and sys.stdout.isatty() and not quiet()


def _job_grid(script, model, start, initial, options: JobOptions):
    from .path_map import job_grid

    return job_grid(script.compile(initial=initial, from_line=options.from_line), model, start)


def _deferred_ctrl_c(runner):
    """While streaming, Ctrl-C (or SIGTERM, SIGHUP: armctl/stop_signals.py) asks the runner to stop
    at its next safe point (between writes), so the records of a frame written are never half
    made; a second one acts at once."""
    import signal

    from ..stop_signals import stop_signals

    def on_stop(signum: int) -> None:
        if signum != signal.SIGINT:
            runner.view.messages.append(f"stopped by {signal.Signals(signum).name}")
        runner.request_stop()

    return stop_signals(on_stop)


class _Display:
    """A rich Live panel on a terminal, plain progress lines elsewhere; throttled.

    While the panel is live it owns the screen: rich redraws it by moving the cursor up over
    the lines it drew last, so a line written past it (a raw write to stderr) makes the next
    redraw land too low and leaves a stray partial panel above the real one.  Every message
    printed during the job therefore goes through ``note``, which prints it above the panel.

    The job's map (``grid``, a path_map.PathGrid, or None) is drawn while the terminal has room
    for it (MAP_MIN_WIDTH × MAP_MIN_HEIGHT, checked at every redraw, so a resize counts); rich
    would crop a panel taller than the screen.
    """

    def __init__(self, title: str, live: bool, console=None, grid=None, footer: str | None = None) -> None:
        self.title, self.live, self.grid, self.footer = title, live, grid, footer
        self._console = console  # tests pass a recording console; None: rich's own (stdout)
        self._live = None
        self._last = 0.0

    def __enter__(self):
        if self.live:
            from rich.live import Live
            from rich.text import Text

            self._live = Live(Text("starting …"), console=self._console, refresh_per_second=10, transient=False)
            self._live.__enter__()
        return self

    def __exit__(self, *exc):
        if self._live is not None:
            live, self._live = self._live, None
            live.__exit__(*exc)

    def note(self, text: str) -> None:
        """A message for stderr that the live panel must not be broken by."""
        if self._live is not None and sys.stderr.isatty():
            from rich.text import Text

            # rich erases the panel, prints the text, redraws the panel below it; the leading
            # newline that moves past an echoed ^C on a plain terminal is not needed here
            self._live.console.print(Text(text.lstrip("\n")), soft_wrap=True)
        else:
            click.echo(text, err=True)

    def update(self, view) -> None:
        now = time.monotonic()
        if self._live is not None:
            if now - self._last >= LIVE_REFRESH_S or view.outcome != "running":
                from .run_panel import render_run

                self._live.update(render_run(view, self.title, self._map_room(), self.footer), refresh=True)  # throttled: draw now
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


def _repeat_note(view, resume: int | None) -> str:
    """What the summary says when the resume line is a repeat block's start (jobflow.resume_line:
    --from-line cannot start inside one): the passes already done run again."""
    loop = getattr(view.first_not_done, "loop", ()) if resume is not None else ()
    if not loop:
        return ""
    return (f" (line {view.resume_line()} is inside a repeat block, in pass {loop[-1] + 1}: the block "
            "runs again from its first pass, so the passes already done are repeated)")


def job_result(view, outcome: str, options: JobOptions, script, estimate):
    """The run's result: the Python API's ``RunResult``, built by the same ``RunResult.of`` —
    ``run --json``'s summary (``to_json``) and what the text summary says."""
    from ..api import RunResult

    return RunResult.of(view, outcome, script.lines(), estimated_job_s=estimate.job_s,
                        resume_command=lambda line: resume_command(options, line))


def _summary(result, view, wall_s: float, estimate, options: JobOptions) -> int:
    """The text summary of ``result`` (the arm time unrounded, from ``view``); the exit code."""
    click.echo(f"frames: {result.frames_sent} of {result.total_frames} sent")
    click.echo(f"time: {wall_s:.1f} s wall")
    if view.arm_time_s is not None:
        actual = view.arm_time_s
        click.echo(f"arm time: {actual:.1f} s from the first frame to the arm at rest; estimated {estimate.job_s:.1f} s "
                   f"({actual / estimate.job_s - 1:+.1%})" if estimate.job_s else f"arm time: {actual:.1f} s")
    click.echo(f"frames confirmed by the arm's reports: {result.frames_by_reports}; by time only: {result.frames_by_time}")
    for message in result.messages:
        click.echo(f"note: {message}", err=True)
    if result.finished:
        click.echo("done: the arm finished the job")
        return result.exit_code
    if result.outcome == "finished, unproven":
        click.echo("finished, unproven: the arm is at rest at the last target, but the FIFO size is not proven; "
                   "run `armctl probe` once")
        return result.exit_code
    sent, done = result.last_line_sent, result.last_line_executed
    click.echo(f"last line sent: {sent if sent is not None else 'none'}")
    click.echo(f"last line known executed: {done if done is not None else 'none'}")
    if result.resume_line is not None:
        click.echo(f"resume with: {result.resume_command}{_repeat_note(view, result.resume_line)}")
    if result.outcome == "interrupted":
        click.echo(f"stopped: interrupted; abort sequence: {options.abort}", err=True)
    else:
        click.echo(f"stopped: {result.outcome}", err=True)
    return result.exit_code
