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

import json
import re
import signal
import sys
import threading
import time
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass

import click

from ..errors import ArmctlError, PortError
from ..protocol import describe
from ..streamer import DEFAULT_LEAD_S, Streamer

EXIT_OK, EXIT_PROBLEMS, EXIT_INTERRUPTED = 0, 1, 130
LIVE_REFRESH_S = 0.1
PLAIN_PROGRESS_S = 2.0
# The least terminal the panel's map is drawn in: its ~24 rows with the map, a few lines of
# notes above; the map's rows are 60 columns with their label.
MAP_MIN_WIDTH, MAP_MIN_HEIGHT = 80, 30


class JobFailed(ArmctlError):
    """The job could not start or did not finish; nothing more to add than the message."""


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


def check_script(script, profile):
    """The same checks as ``armctl lint`` over the whole script (a ``ScriptSnapshot``) before
    anything is sent: any error prints every finding and exits 1; warnings are shown and the
    job goes on."""
    from ..lint.engine import lint_lines

    from ..output import quiet

    report = lint_lines(script.lines(), script.name, profile)
    shown = [d for d in report.diagnostics if d.severity == "error"] if quiet() else report.diagnostics  # -q: no warnings
    _refuse_on_errors(shown, report.errors)
    return report


def check_from_line(script, from_line: int) -> None:
    """A resume line the compiler cannot start at (inside an arc, inside a repeat block, past
    the end) is an error like any other: nothing is sent."""
    if from_line <= 1:
        return
    check = script.compile(from_line=from_line)
    check.finish()
    _refuse_on_errors([d for d in check.diagnostics if d.severity == "error"], check.error_count)


def _refuse_on_errors(diagnostics, errors: int) -> None:
    for diagnostic in diagnostics:
        click.echo(diagnostic.render(), err=True)
    if errors:
        click.echo(f"{errors} error{'s' if errors != 1 else ''}: nothing was sent to the arm", err=True)
        sys.exit(EXIT_PROBLEMS)


def estimate_job(script, model, start, lead_s, baud, from_line=1, initial=None):
    """The estimate of the job in ``script`` (a ``ScriptSnapshot``); a job whose motion time
    passes ``MAX_JOB_MOTION_S`` is refused (E012 at the line where it does; exit 1)."""
    from ..estimate import JobEstimator, motion_time_overrun

    estimator = JobEstimator(model, start, lead_s, baud)
    compilation = script.compile(initial=initial, from_line=from_line)
    for statement in compilation:
        estimator.add(statement.command)
        overrun = motion_time_overrun(statement, estimator.result.motion_s)
        if overrun is not None:
            _refuse_on_errors([overrun], 1)
    # This pass is the stream's twin (same snapshot, same initial state, same from_line): if it
    # compiled cleanly, so will the stream, frame for frame; the arm's reported state can make
    # a line fail that passed the check (a G91 offset from the real pose), and then nothing goes.
    if compilation.error_count:
        _refuse_on_errors([d for d in compilation.diagnostics if d.is_error], compilation.error_count)
    return estimator.result


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
    """Wait for all nine status kinds and two more rotations (so a corrupted first frame of a
    kind has been replaced or held back, H9); resume an arm that twice reports it is paused, as
    its control mode needs (``job.resume_frames``), and let a move the pause froze finish, so
    the start pose is where the arm rests."""
    if not link.wait_until(lambda s: s.complete, timeout_s):
        _, received, _, frames = link.snapshot()
        heard = "nothing" if received == 0 else f"{received} bytes, {frames} status frames"
        raise JobFailed(f"no complete status from {link.url} within {timeout_s:g} s (received {heard}); nothing was sent")
    _wait_rotations(link, 2, timeout_s)
    if _paused_twice(link, timeout_s):
        from ..job import resume_frames

        frames = resume_frames(control_on_arrival)
        click.echo("armctl: the arm reports it is paused: sending " + (
            "a reset host connector (it acts on control frames as they land: nothing left queued runs twice) and "
            if len(frames) > 1 else "") + "one pause toggle to resume it", err=True)
        for command in frames:
            frame = command.encode()
            link.write(frame)
            if log is not None:
                log.write(json.dumps({"t": 0.0, "dir": "tx", "hex": frame.hex(), "resume": True}) + "\n")
        if not link.wait_until(lambda s: s.paused is False, max(timeout_s, 1.0)):
            raise JobFailed("the arm stayed paused after a pause toggle; nothing else was sent")
        _wait_rotations(link, 1, timeout_s)
        if control_on_arrival:
            _wait_still(link, timeout_s)
    return link.snapshot()[0]


RESUME_SETTLE_S = 120.0  # the longest a move frozen by a pause may take to finish after the resume


def _wait_still(link, timeout_s: float) -> None:
    """Until the arm reports the same position and joints over two rotations (a frozen move
    finished), at most ``RESUME_SETTLE_S``."""
    def pose():
        state = link.snapshot()[0]
        return state.position_mm, tuple(state.joints_deg)

    deadline_s = link.clock() + RESUME_SETTLE_S
    before = pose()
    while link.clock() < deadline_s:
        _wait_rotations(link, 2, timeout_s)
        now = pose()
        if now == before:
            return
        before = now
    raise JobFailed(f"the arm did not come to rest within {RESUME_SETTLE_S:g} s of the resume; nothing else was sent")


def _wait_rotations(link, rotations: int, timeout_s: float) -> None:
    frames = link.snapshot()[3]
    link.wait_until(lambda s: s.frames >= frames + 9 * rotations, timeout_s)


def _paused_twice(link, timeout_s: float) -> bool:
    """Paused in two consecutive pause reports (the engine's rule, ``agreed_pause``): one flipped
    byte must not make armctl toggle."""
    from ..job import agreed_pause

    state = link.snapshot()[0]
    if not state.paused:
        return False
    seen = state.last_seen.get(4)
    link.wait_until(lambda s: s.last_seen.get(4) != seen, timeout_s)
    return agreed_pause((state.paused, link.snapshot()[0].paused)) is True


def start_from_state(model, state):
    """The streamer's start pose and the compiler's initial state, from the arm's report."""
    from ..script import InitialState

    joints = tuple(state.joints_deg)
    pose = model.reported_pose(state.position_mm, joints, float(state.pwm_us), tuple(state.worktable_mm))
    initial = InitialState(pose=tuple(pose.cartesian), joints_deg=joints, pwm_us={1: float(state.pwm_us)})
    return pose, initial


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
    from ..motion import MotionModel
    from ..profile import load_profile
    from ..link import fifo_proven
    from ..runner import JobRunner, RunView

    profile = load_profile(options.profile_path)
    report = check_script(script, profile)
    check_from_line(script, options.from_line)
    model = MotionModel(profile)
    if options.dry_run:
        return dry_run(options, script, model)
    # A job too long to run (E012) was refused by check_script's lint, which judges the motion
    # time as estimate_job does; the estimate from the arm's own pose below judges it again over
    # the whole expansion, before anything is sent.  No third pass here.

    link, baud = connect(options.port, options.baud, profile=profile)
    with link, (_log_file(options.log_path) if options.log_path else nullcontext()) as log:
        state = read_arm(link, options.timeout_s, log, profile.connector.control_on_arrival)
        start, initial = start_from_state(model, state)
        estimate = estimate_job(script, model, start, options.lead_s, baud, options.from_line, initial)
        if estimate.frames == 0:
            click.echo("nothing to send: the script has no frames" + (f" from line {options.from_line}" if options.from_line > 1 else ""))
            return EXIT_OK
        streamer = Streamer(model, start, lead_s=options.lead_s, baud=baud)
        view = RunView(total_frames=estimate.frames, estimated_job_s=estimate.job_s, total_lines=report.lines, lead_s=options.lead_s,
                       capacity=streamer.limit_frames, remaining_motion_s=estimate.motion_s)
        statements = script.compile(initial=initial, from_line=options.from_line)
        runner = JobRunner(link, streamer, statements, view, log=log, fifo_proven=fifo_proven(link.url, profile.connector))
        # the live panel's map: the same snapshot compiled the same way, sampled once before the
        # first frame (bounded: path_map.MAP_MAX_FRAMES); no panel, no map
        grid = _job_grid(script, model, start, initial, options) if _live(options) else None
        link.on_status = runner.on_status
        wall_start = time.monotonic()
        outcome = _stream(runner, options, view, grid)
        wall_s = time.monotonic() - wall_start
        return _summary(view, outcome, wall_s, estimate, options, script)


def _stream(runner, options: JobOptions, view, grid=None) -> str:
    from ..runner import abort_frames

    title = f"armctl run {options.script}"
    from ..output import quiet

    display = _Display(title, _live(options), grid=grid)
    runner.on_update = (lambda view: None) if quiet() else display.update  # -q: the summary only
    with _deferred_ctrl_c(runner), display:
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
        why = runner.failure or "interrupted"
        display.note(f"\narmctl: {why}: no more frames are sent; sending the abort sequence "
                     f"({options.abort}) and waiting for the arm to come to rest …")
        try:
            runner.abort(abort_frames(options.abort, runner.streamer.control_on_arrival))
        except KeyboardInterrupt:
            pass
        except Exception as error:  # the abort itself failed: say so, the summary still follows
            view.messages.append(f"the abort did not complete: {type(error).__name__}: {error}")
        if runner.job.outcome is None and runner.failure:  # the abort was cut short: the engine did not end it
            view.outcome = "failed"
            view.messages.append(runner.failure)
        return view.outcome  # "interrupted", "failed", or "port lost" if the abort could not be sent


def _live(options: JobOptions) -> bool:
    """The rich panel, rather than plain progress lines: asked for, stdout is a terminal, not -q."""
    from ..output import quiet

    return options.live and sys.stdout.isatty() and not quiet()


def _job_grid(script, model, start, initial, options: JobOptions):
    from .path_map import job_grid

    return job_grid(script.compile(initial=initial, from_line=options.from_line), model, start)


@contextmanager
def _deferred_ctrl_c(runner):
    """While streaming, Ctrl-C (or SIGTERM, SIGHUP) asks the runner to stop at its next safe point
    (between writes), so the records of a frame written are never half made; a second one acts at once."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    # SIGTERM (timeout, systemd, a CI cancelling) and SIGHUP (the terminal closed) stop a job
    # the same way: an arm left running with no summary and no resume line is the worst ending.
    signals = [signal.SIGINT] + [getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)]

    def stop(signum, _frame):
        if signum != signal.SIGINT:
            runner.view.messages.append(f"stopped by {signal.Signals(signum).name}")
        runner.request_stop()

    previous = {number: signal.getsignal(number) for number in signals}
    for number in signals:
        signal.signal(number, stop)
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


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

    def __init__(self, title: str, live: bool, console=None, grid=None) -> None:
        self.title, self.live, self.grid = title, live, grid
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

                self._live.update(render_run(view, self.title, self._map_room()), refresh=True)  # throttled: draw now
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


_BLOCK_LINE = re.compile(r"^\s*(?:N\d+\s+)?O(?:<[^>]*>|\d+)\s*(repeat|endrepeat)\b", re.IGNORECASE)


def outermost_block_start(lines, line: int) -> int | None:
    """The opening line of the outermost repeat block around ``line``, if any (``lines``: the
    script's lines, e.g. ``ScriptSnapshot.lines()`` — the same text that was sent)."""
    depth, start = 0, None
    for number, text in enumerate(lines, 1):
        match = _BLOCK_LINE.match(text)
        if match is None:
            continue
        if match.group(1).lower() == "repeat":
            if depth == 0:
                start = number
            depth += 1
        elif depth:
            depth -= 1
            if depth == 0 and start is not None and start <= line <= number:
                return start
    return None


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


def _summary(view, outcome: str, wall_s: float, estimate, options: JobOptions, script) -> int:
    sent = view.last_sent.line if view.last_sent is not None else None
    done = view.last_done.line if view.last_done is not None else None
    click.echo(f"frames: {view.frames_sent} of {view.total_frames} sent")
    click.echo(f"time: {wall_s:.1f} s wall")
    if view.arm_done_s is not None:
        actual = view.arm_done_s - view.started_s
        click.echo(f"arm time: {actual:.1f} s from the first frame to the arm at rest; estimated {estimate.job_s:.1f} s "
                   f"({actual / estimate.job_s - 1:+.1%})" if estimate.job_s else f"arm time: {actual:.1f} s")
    click.echo(f"frames confirmed by the arm's reports: {view.frames_by_reports}; by time only: {view.frames_by_time}")
    for message in view.messages:
        click.echo(f"note: {message}", err=True)
    if outcome == "finished":
        click.echo("done: the arm finished the job")
        return EXIT_OK
    if outcome == "finished, unproven":
        click.echo("finished, unproven: the arm is at rest at the last target, but the FIFO size is not proven; "
                   "run `armctl probe` once")
        return EXIT_PROBLEMS
    click.echo(f"last line sent: {sent if sent is not None else 'none'}")
    click.echo(f"last line known executed: {done if done is not None else 'none'}")
    resume = view.resume_line()
    if resume is not None:
        loop = getattr(view.first_not_done, "loop", ())
        where = ""
        if loop:
            # --from-line cannot start inside a repeat block: resume at its outermost start.
            resume = outermost_block_start(script.lines(), resume) or resume
            where = (f" (line {view.resume_line()} is inside a repeat block, in pass {loop[-1] + 1}: the block "
                     "runs again from its first pass, so the passes already done are repeated)")
        click.echo(f"resume with: {resume_command(options, resume)}{where}")
    if outcome == "interrupted":
        click.echo(f"stopped: interrupted; abort sequence: {options.abort}", err=True)
        return EXIT_INTERRUPTED
    click.echo(f"stopped: {outcome}", err=True)
    return EXIT_PROBLEMS
