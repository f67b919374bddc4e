"""The ``armctl`` command: click wiring and nothing else.

Strategy: each command parses its options, calls into the package and maps the outcome to an
exit code.  Heavy modules (lark, rich, serial) are imported inside the command that needs
them, so ``armctl --help`` stays fast.  Every error a user can cause is an ``ArmctlError`` or
an ``OSError`` and becomes one line on stderr with an exit code — never a traceback.

Exit codes: 0 success, 1 the input had problems (script errors, lint findings, a job that did
not finish), 2 usage errors and unreadable files, 130 interrupted by Ctrl-C, 141 the program
reading our output went away (``| head``).
"""

from __future__ import annotations

from ..host.stop_signals import command_running, install_for_program, is_the_program

if is_the_program():  # the armctl command (not a test or a script importing this): before any heavy import
    install_for_program()

import json  # noqa: E402  (the handlers first: a signal in the first instant is exit 130, no traceback)
import sys  # noqa: E402
from contextlib import contextmanager  # noqa: E402
from itertools import islice  # noqa: E402

import click  # noqa: E402

from .. import __version__  # noqa: E402
from ..bench import SCENARIO_NAMES as BENCH_SCENARIOS  # the names only: imports nothing else
from .cli_types import NamedFile, OutputFile, number
from ..errors import ArmctlError, ConfigError, ProfileError
from ..errors import EXIT_BROKEN_PIPE, EXIT_INTERRUPTED, EXIT_PROBLEMS, EXIT_USAGE, UsageFailure, exit_code_for
from ..core.limits import BAUD_RANGE, BENCH_JOBS_RANGE, BENCH_LEAD_RANGE_S, LEAD_RANGE_S, LINE_RANGE, START_TIMEOUT_RANGE_S, STATUS_TIMEOUT_RANGE_S, TCP_PORT_RANGE



class ArmctlGroup(click.Group):
    """Turns the errors a user can cause into a message and an exit code."""

    def main(self, *args, **kwargs):
        _require_stdout()
        _tolerant_output()
        return super().main(*args, **kwargs)

    def _main_shell_completion(self, ctx_args, prog_name, complete_var=None):
        """click's answer to the shell (the hook ``main`` calls first): a request it cannot read is
        one line and exit 2, not its traceback (armctl/ui/completion.py's ``request_errors``)."""
        from .completion import complete_var as derived, request_errors

        with _exit_codes(), request_errors(complete_var or derived(prog_name)):
            super()._main_shell_completion(ctx_args, prog_name, complete_var)

    def make_context(self, *args, **kwargs):
        """The group's own options (``--help``, ``--version``) write before any command runs:
        a full disk or a reader gone is the same exit there (2, 141) as in a command."""
        with _exit_codes():
            return super().make_context(*args, **kwargs)

    def invoke(self, ctx: click.Context):
        with _exit_codes():
            try:
                with command_running():  # a stop signal is Ctrl-C from here (armctl/host/stop_signals.py)
                    return super().invoke(ctx)
            finally:
                _flush_stdout()


@contextmanager
def _exit_codes():
    """Every error a user can cause, as one line on stderr and its exit code."""
    try:
        yield
    except ArmctlError as error:
        _fail(str(error), exit_code_for(error))
    except KeyboardInterrupt:
        _fail("interrupted", EXIT_INTERRUPTED)
    except BrokenPipeError:
        _reader_went_away()
    except OSError as error:
        _fail(_os_error_text(error), EXIT_USAGE)


def _flush_stdout() -> None:
    """Whatever the command wrote must reach its reader: a full disk (``compile > /dev/full``)
    is an error (exit 2), never a silent success with half the frames."""
    flush = getattr(sys.stdout, "flush", None)  # None: stdout replaced by something odd (a test)
    if flush is None:
        return
    try:
        flush()
    except BrokenPipeError:
        raise
    except OSError as error:
        raise UsageFailure(f"cannot write the output: {error.strerror or error}") from None
    except ValueError:  # stdout closed by the command itself
        pass


def _require_stdout() -> None:
    """Every command writes its data, its summary or its banner on stdout: started with stdout
    closed (``>&-``; Python then has ``sys.stdout`` None) or open for reading only (``1<file``)
    it would lose them and exit 0, or fail at its first write after the arm was touched.  Exit 2
    first, saying so."""
    if sys.stdout is None:
        _fail("cannot write the output: standard output is closed (to drop it, redirect it to "
              "/dev/null)", EXIT_USAGE)
    try:
        import fcntl
        import os

        read_only = fcntl.fcntl(sys.stdout.fileno(), fcntl.F_GETFL) & os.O_ACCMODE == os.O_RDONLY
    except (ImportError, OSError, ValueError, AttributeError):  # Windows; a test runner's stdout
        return
    if read_only:
        _fail("cannot write the output: standard output is open for reading only (to drop it, redirect it "
              "to /dev/null)", EXIT_USAGE)


def _tolerant_output() -> None:
    """Every command may print anything (…, →, °, a user's file name) to any terminal: on an
    output whose encoding lacks a character (PYTHONIOENCODING=latin-1, an ASCII locale) it is
    written as an escape (``\\u2026``) instead of raising UnicodeEncodeError.  Done once here,
    at the entry point, so click, rich and plain prints all inherit it."""
    for name in ("stdout", "stderr"):
        reconfigure = getattr(getattr(sys, name, None), "reconfigure", None)
        if reconfigure is not None:
            try:
                reconfigure(errors="backslashreplace")
            except (ValueError, OSError):  # a closed or exotic stream: leave it as it is
                pass


def _reader_went_away():
    """``armctl compile job | head -1``: the reader has what it wanted; end quietly, as a
    program killed by SIGPIPE would (exit 141), without a message about it."""
    import os

    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())  # Python's final flush of stdout must not fail again
    sys.exit(EXIT_BROKEN_PIPE)


def _fail(message: str, code: int):
    click.echo(f"armctl: {message}", err=True)
    sys.exit(code)


def _os_error_text(error: OSError) -> str:
    name = f"{error.filename}: " if error.filename else ""
    return f"{name}{error.strerror or error}"


@click.group(cls=ArmctlGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, "--version", prog_name="armctl")
@click.option("-v", "--verbose", is_flag=True, help="Log to stderr why `run` paces as it does (what each write waited for, what proved frames done).")
@click.option("-q", "--quiet", is_flag=True, help="Print only errors, the summary and the data asked for: no banner, progress or warnings.")
def main(verbose, quiet):
    """Drive a 6-axis desktop robot arm over its serial connector.

    Without --port (or ARMCTL_PORT, or `port` in armctl.toml) commands talk to the built-in
    simulator.
    """
    _configure_output(click.get_current_context())


def _configure_output(ctx: click.Context) -> None:
    """``-v``/``-q`` as given so far (before or after the subcommand), on the root context
    where ``armctl.ui.output.quiet`` reads them."""
    from .output import configure

    root = ctx.find_root()
    verbose, quiet = bool(root.params.get("verbose")), bool(root.params.get("quiet"))
    if verbose and quiet:
        raise click.UsageError("choose -v or -q, not both")
    configure(verbose, quiet)


def _late_flag(ctx: click.Context, param: click.Parameter, value: bool) -> None:
    """``armctl run job.txt -q``: the group's flag given after the subcommand."""
    if value:
        ctx.find_root().params[param.name] = True
        _configure_output(ctx)


def _accept_output_flags_after(group: click.Group) -> None:
    """Every subcommand takes ``-v``/``-q`` too, meaning exactly what they mean before it."""
    for command in group.commands.values():
        if isinstance(command, click.Group):
            _accept_output_flags_after(command)
            continue
        taken = {name for param in command.params for name in getattr(param, "opts", ())}
        for flag, name, text in (("-v", "verbose", "The same as `armctl -v`."), ("-q", "quiet", "The same as `armctl -q`.")):
            if flag not in taken and f"--{name}" not in taken:
                command.params.append(click.Option([flag, f"--{name}"], is_flag=True, expose_value=False,
                                                   callback=_late_flag, help=text))


def _read_input(path: str) -> bytes:
    """All of ``path`` (``-``: stdin), bounded (armctl/host/inputs.py): too long is exit 2."""
    from ..host.inputs import read_bounded, read_file_bounded

    if path == "-":
        return read_bounded(sys.stdin.buffer, "<stdin>")
    try:
        return read_file_bounded(path)
    except OSError as error:
        raise UsageFailure(f"cannot read {path}: {error.strerror or error}") from None


@main.command()
@click.argument("source", default="-", metavar="[FILE|-]")
@click.option("--json", "as_json", is_flag=True, help="JSON lines: one object per frame or run of bytes (the summary stays on stderr).")
def decode(source: str, as_json: bool):
    """Name every frame in hex text, raw bytes or an armctl log.

    Finds 48-byte command frames and 9-byte status frames in any mix, prints one readable
    line per frame (offset, family, command and fields with units) and marks bytes that
    belong to no frame.  A run --log's frames come with their time and direction
    (host→arm, arm→host), in the log's order.  The input is read as it is decoded.
    """
    from .decode_output import print_decoded

    sys.exit(print_decoded(source, as_json))


def _read_script(path: str):
    """The script at ``path`` (``-``: stdin) read once, bounded, as an immutable
    ``ScriptSnapshot``: every pass of the command compiles this snapshot, never the file
    again (what was checked is what is sent or written).  Unreadable or too long: exit 2."""
    from ..script import read_script

    try:
        return read_script(path)
    except OSError as error:
        raise UsageFailure(f"cannot read {path}: {error.strerror or error}") from None


def _refuse_same_file(output: str, script: str, option: str) -> None:
    """An output (``-o``, ``--log``) that is the script itself: exit 2, nothing written."""
    from ..host.outputs import SameFileError, refuse_same_file

    try:
        refuse_same_file(output, script, option)
    except SameFileError as error:
        raise UsageFailure(str(error)) from None


def _report_script_errors(compilation) -> None:
    """Print every diagnostic of a failed check and exit 1; nothing else is written."""
    for diagnostic in compilation.diagnostics:
        click.echo(diagnostic.render(), err=True)
    errors = compilation.error_count
    click.echo(f"{errors} error{'s' if errors != 1 else ''}: nothing was written", err=True)
    sys.exit(EXIT_PROBLEMS)


@main.command(name="compile")
@click.argument("script", metavar="SCRIPT")
@click.option("--format", "fmt", type=click.Choice(["hex", "json", "bin"]), default="hex", show_default=True,
              help="hex: one frame per line, 96 hex digits; json: one object per frame; bin: the raw bytes.")
@click.option("--json", "as_json", is_flag=True, help="The same as --format json (armctl's one JSON spelling).")
@click.option("-o", "--output", type=NamedFile(dir_okay=False, writable=True, dash_is_stdout=True),
              help="Write here instead of stdout (- : stdout).")
def compile_command(script: str, fmt: str, as_json: bool, output: str | None):
    """Check a motion script, then print the exact frames the arm would receive.

    The whole script is checked first; with any error nothing is written and the exit code
    is 1. SCRIPT may be - for standard input. -o writes the file only after a clean check,
    all at once (a temporary file renamed over it), and never over the script itself.
    """
    from .formats import frame_record

    if as_json:
        given = click.get_current_context().get_parameter_source("fmt") != click.core.ParameterSource.DEFAULT
        if given and fmt != "json":
            raise click.UsageError(f"--json is --format json: it cannot be combined with --format {fmt}")
        fmt = "json"
    if fmt == "bin" and output is None and sys.stdout.isatty():
        raise UsageFailure("refusing to write binary frames to a terminal: use -o FILE or a pipe")
    if output is not None:
        _refuse_same_file(output, script, "-o")
    source_script = _read_script(script)
    # One pass: the frames go to a temporary file while the script compiles; it becomes the
    # output (or is copied to stdout) only if the whole script compiled without errors.
    from ..host.outputs import PendingOutput

    with PendingOutput(output, binary=fmt == "bin") as pending:
        out = pending.stream
        compilation = source_script.compile()
        if fmt == "json":
            def record(statement) -> str:
                source = {"file": statement.span.file, "line": statement.line, "text": statement.span.text.rstrip("\r\n")}
                return json.dumps(frame_record(statement.command, statement.command.encode(), source)) + "\n"
            pieces = map(record, compilation)
        elif fmt == "hex":
            pieces = (statement.command.encode().hex() + "\n" for statement in compilation)
        else:
            pieces = (statement.command.encode() for statement in compilation)
        empty = b"" if fmt == "bin" else ""
        # written 4,096 frames at a time: a write per frame costs more than encoding it
        for batch in iter(lambda: list(islice(pieces, 4096)), []):
            out.write(empty.join(batch))
        if compilation.error_count:
            _report_script_errors(compilation)  # exits 1; the pending output is discarded
        pending.commit()


# --- commands that talk to a port -------------------------------------------------------------

port_option = click.option(
    "--port", "port", metavar="URL",
    help="Device path or pyserial URL (socket://, rfc2217://, sim://?speed_factor=1.3). "
    "Default: ARMCTL_PORT, else `port` in the project's armctl.toml, else in yours (`armctl config`), "
    "else the built-in simulator.",
)
baud_option = click.option("--baud", type=number(*BAUD_RANGE, whole=True), default=None, help="Line rate [default: `baud` in the project's or your armctl.toml, else 9600].")


def _connect(port: str | None, baud: int | None, **link_options):
    from ..host.link import connect
    from .output import announce

    return connect(port, baud, announce=announce, **link_options)


@main.command()
@port_option
@baud_option
@click.option("--once", is_flag=True, help="Read the arm as a job does before its first frame (all 9 status kinds, then until two rotations agree), print it, exit.")
@click.option("--watch", is_flag=True, help="A live view, refreshed 12 times a second, until Ctrl-C.")
@click.option("--json", "as_json", is_flag=True, help="JSON (one object; with --watch, JSON lines).")
@click.option("--timeout", type=number(*STATUS_TIMEOUT_RANGE_S), default=2.0, show_default=True,
              help="Seconds to wait for the arm's status (with --watch into a pipe: for the first complete one).")
def status(port, baud, once, watch, as_json, timeout):
    """Show the arm's decoded status frames (position, joints, PWM, pause, SD program)."""
    from .status_watch import print_once, watch_status

    if once and watch:
        raise UsageFailure("choose --once or --watch, not both")
    link, baud = _connect(port, baud)
    with link:
        if watch:
            from ..host.link import require_wall_clock

            require_wall_clock(link, "status --watch")
            watch_status(link, baud, as_json, timeout)
        else:
            print_once(link, baud, timeout, as_json)


@main.command()
@click.option("--json", "as_json", is_flag=True, help="One JSON array of {device, description, hwid} objects.")
def ports(as_json):
    """List the serial ports found on this machine (device, description, hardware id)."""
    from serial.tools import list_ports

    found = sorted(list_ports.comports(), key=lambda p: p.device)
    if as_json:
        records = [{"device": p.device, "description": p.description, "hwid": p.hwid} for p in found]
        click.echo(json.dumps(records, ensure_ascii=False))
    if not found:
        click.echo("no serial ports found (the built-in simulator is always there: --port sim://)", err=as_json)
    if not as_json:
        for info in found:
            click.echo(f"{info.device}\t{info.description}\t{info.hwid}")


@main.command()
@click.argument("script", metavar="SCRIPT")
@port_option
@baud_option
@click.option("--lead", "lead_s", type=number(*LEAD_RANGE_S), default=2.0, show_default=True,
              help="Seconds of motion kept queued ahead of the arm (how long it keeps moving after Ctrl-C).")
@click.option("--from-line", "from_line", type=number(*LINE_RANGE, whole=True), default=1, help="Start at this line, with the modal state the lines before it set.")
@click.option("--dry-run", is_flag=True, help="Check, print the frames and the estimate; open no port.")
@click.option("--log", "log_path", type=OutputFile(writable=True), help="JSON lines of every frame written and read (armctl decode reads it).")
@click.option("--no-live", is_flag=True, help="Plain progress lines instead of the live panel.")
@click.option("--abort", type=click.Choice(["pause", "reset-connector", "none"]), default="pause", show_default=True,
              help="What Ctrl-C sends after it stops feeding (see README: Stopping a job).")
@click.option("--profile", "profile_path", type=click.Path(exists=True, dir_okay=False), help="Arm profile (TOML).")
@click.option("--timeout", "timeout_s", type=number(*START_TIMEOUT_RANGE_S), default=3.0, show_default=True, help="Seconds to wait for the arm's status before starting.")
@click.option("--json", "as_json", is_flag=True, help="JSON lines on stdout: progress events, then one summary object.")
@click.option("--resume", "resume_log", type=click.Path(exists=True, dir_okay=False), metavar="LOG",
              help="Continue the job a --log of this script records, from the line the arm proves it reached.")
@click.option("--other-port", is_flag=True, help="With --resume: --port is the arm LOG's job ran on, moved to another port.")
def run(script, port, baud, lead_s, from_line, dry_run, log_path, no_live, abort, profile_path, timeout_s, as_json, resume_log,
        other_port):
    """Check a motion script, then stream it to the arm without overflowing its buffer.

    SCRIPT (a file, or - for standard input) is read once: what was checked is what is sent.
    """
    from .run_job import JobOptions, refuse_with_dry_run, run_job

    if log_path is not None:
        _refuse_same_file(log_path, script, "--log")
    if dry_run:
        refuse_with_dry_run(as_json, resume_log)
    snapshot = _read_script(script)
    options = JobOptions(script, port, baud, lead_s, from_line, dry_run, log_path, not no_live, abort, profile_path, timeout_s,
                         as_json, resume_log, other_port)
    sys.exit(run_job(options, snapshot, _connect))


@main.command()
@click.argument("script", metavar="SCRIPT")
@click.option("--lead", "lead_s", type=number(*LEAD_RANGE_S), default=2.0, show_default=True, help="The lead run would use.")
@baud_option
@click.option("--profile", "profile_path", type=click.Path(exists=True, dir_okay=False), help="Arm profile (TOML).")
@click.option("--json", "as_json", is_flag=True, help="One JSON object.")
def estimate(script, lead_s, baud, profile_path, as_json):
    """How long a job takes on the arm: time, frames, path, line- vs arm-bound, peak queue.

    SCRIPT may be - for standard input.
    """
    from ..host.calibration import arm_profile, quiet_port
    from ..core.motion import MotionModel
    from .run_job import check_script, configured_baud, plan_job, print_estimate

    snapshot = _read_script(script)
    port = quiet_port(None)  # the configured port, its arm read once (None: it names none)
    profile = arm_profile(profile_path, port=port)
    checked = check_script(snapshot, profile)
    result = plan_job(checked, MotionModel(profile), lead_s, baud or configured_baud(port)).estimate
    if as_json:
        click.echo(json.dumps(result.to_json()))
    else:
        print_estimate(result, f"{script} (from the profile's fixed pose 0; the first move depends on where the arm is):")
        if not profile.connector.is_default("speed_factor"):  # the configured port's arm (armctl config)
            click.echo(f"  note: the arm's speed_factor {profile.connector.speed_factor:g} "
                       f"({profile.source_of('connector.speed_factor')})")


_one_line_options = [
    port_option, baud_option,
    click.option("--profile", "profile_path", type=click.Path(exists=True, dir_okay=False), help="Arm profile (TOML)."),
    click.option("--timeout", "timeout_s", type=number(*START_TIMEOUT_RANGE_S), default=3.0, show_default=True,
                 help="Seconds to wait for the arm's status before starting."),
    click.option("--json", "as_json", is_flag=True, help="The result as one JSON object (as run --json's summary)."),
]


def _with_one_line_options(command):
    for option in reversed(_one_line_options):
        command = option(command)
    return command


@main.command()
@click.argument("words", nargs=-1, metavar="WORD=VALUE...")
@_with_one_line_options
def move(words, port, baud, profile_path, timeout_s, as_json):
    """Move the arm with one line, as Arm.move does: armctl move z=200 [f=3000].

    Words: x y z (mm) a b c (deg) for a straight line (G1), or j1…j6 (deg) for a joint move
    (G6); u v external axes, s PWM (µs), t its channel, h smoothing, f speed (mm/min, or deg/s
    for joints; default: the profile's [speed] default).  Words left out keep the arm's
    reported values.  Returns when the arm's reports prove it at rest at the target.
    """
    from .one_line import move_words, one_line_job

    keywords = move_words(words)
    one_line_job(port, baud, profile_path, timeout_s, as_json, lambda arm: arm.move(**keywords), _connect)


@main.command()
@_with_one_line_options
def home(port, baud, profile_path, timeout_s, as_json):
    """Go to the profile's fixed pose 0 (POSE 0) and wait until the arm is proven at rest there."""
    from .one_line import one_line_job

    one_line_job(port, baud, profile_path, timeout_s, as_json, lambda arm: arm.home(), _connect)


@main.command()
@click.option("--pty", "use_pty", is_flag=True, help="Serve the simulated arm on a new pseudo-terminal and print its path.")
@click.option("--tcp", "tcp_port", type=number(*TCP_PORT_RANGE, whole=True),
              help="Serve on 127.0.0.1:PORT (socket://127.0.0.1:PORT): one client at a time, the same arm.")
@click.option("--url", "sim_url", default="sim://", show_default=True, help="Simulator options, as in sim://?speed_factor=1.3&loss=0.05.")
@click.option("--stats", "stats_path", type=NamedFile(dir_okay=False, writable=True), default=None,
              help="On exit, write what the arm saw (frames landed, dropped, run) as JSON to this file (--pty).")
def sim(use_pty, tcp_port, sim_url, stats_path):
    """Run the built-in simulated arm for other programs to talk to."""
    from ..sim.bridge import INTERRUPTED, serve_pty, serve_tcp
    from ..sim.protocol_sim import parse_sim_url

    if bool(use_pty) == bool(tcp_port):
        raise UsageFailure("choose one of --pty or --tcp PORT")
    try:
        options = parse_sim_url(sim_url)
        if isinstance(options.profile, str):  # read now, once, not when the first client connects
            from dataclasses import replace

            from ..host.port_choice import read_sim_profile

            options = replace(options, profile=read_sim_profile(options))
    except (ConfigError, ProfileError) as error:
        raise ConfigError(f"--url: {error}") from None
    if options.virtual_clock:
        raise UsageFailure("a served simulator runs in real time: drop clock=virtual from --url")
    if stats_path is not None and not use_pty:
        raise UsageFailure("--stats goes with --pty")

    def ready(where: str) -> None:
        click.echo(f"simulated arm on {where} (Ctrl-C to stop)")

    if use_pty:
        from ..sim.model import SimulatedArm

        model, arms = SimulatedArm(options), []
        try:
            ended = serve_pty(options, ready, keep_serving=True, model=model, on_arm=arms.append)
        finally:
            if stats_path is not None and arms:
                from ..sim.stats import write_stats

                write_stats(stats_path, model, arms[0].clock_start_s, arms[0].time_scale)
    else:
        ended = serve_tcp(tcp_port, options, ready, keep_serving=True)
    if ended == INTERRUPTED:  # the bridge closed what it opened; Ctrl-C exits 130 like every command
        raise KeyboardInterrupt


# --- armctl serve (issue 25): the arm on the network; the server lives in armctl/server/ ------
@main.command()
@click.option("--arm", "arm_specs", multiple=True, metavar="NAME=PORT",
              help="An arm to serve (repeatable), e.g. --arm 'a=sim://?speed=20' [default: the configured port as `arm`].")
@click.option("--listen", default="127.0.0.1:8765", show_default=True, metavar="HOST:PORT",
              help="Where to listen; anything but loopback needs the token (see docs/server.md).")
@click.option("--token-file", type=click.Path(dir_okay=False), help="Read the token from this file (also on loopback).")
@click.option("--journal-dir", type=click.Path(file_okay=False), help="Where each arm's job journals go [default: the user data dir].")
@click.option("--profile", "profile_path", type=click.Path(exists=True, dir_okay=False), help="Arm profile (TOML) for every arm.")
@click.option("--lead", "lead_s", type=number(*LEAD_RANGE_S), default=2.0, show_default=True, help="Seconds of motion kept queued ahead of each arm.")
def serve(arm_specs, listen, token_file, journal_dir, profile_path, lead_s):
    """Serve arms over HTTP + WebSocket, with a web page at / (needs the `serve` extra)."""
    from ..server import EXTRA_MISSING, extra_installed

    if not extra_installed():
        raise UsageFailure(EXTRA_MISSING)
    from ..server.run import serve as serve_arms

    serve_arms(arm_specs, listen, token_file, journal_dir, profile_path, lead_s, say=lambda text: click.echo(text, err=True))


def _register_packaged_commands() -> None:
    """Commands that live with their package; their modules import only click at load."""
    from .config import config
    from .completion import completion
    from ..jog.command import jog
    from ..lint.command import lint
    from ..plot.command import plot
    from ..probe.command import probe

    main.add_command(config)
    main.add_command(completion)
    main.add_command(jog)
    main.add_command(lint)
    main.add_command(plot)
    main.add_command(probe)


_register_packaged_commands()


@main.command()
@click.option("--quick", "size", flag_value="quick", help="Smaller jobs, a few seconds (CI).")
@click.option("--size", "size", type=click.Choice(["full", "quick", "test"]), default="full", hidden=True)
@click.option("--scenario", "scenario_names", multiple=True, type=click.Choice(BENCH_SCENARIOS), metavar="NAME",
              help=f"Run only this scenario (repeatable): {', '.join(BENCH_SCENARIOS)}.")
@click.option("--lead", "lead_s", type=number(*BENCH_LEAD_RANGE_S), default=2.0, show_default=True,
              metavar="S", help="armctl's lead in seconds.")
@click.option("--json", "as_json", is_flag=True, help="Print every cell as JSON.")
@click.option("--jobs", type=number(*BENCH_JOBS_RANGE, whole=True), default=None, metavar="N",
              help="Parallel processes (default: one per CPU).")
@click.option("--realtime", is_flag=True,
              help="The real-time benchmark instead: jobs through `armctl sim --pty` on the wall clock (~2 min).")
def bench(size, scenario_names, lead_s, as_json, jobs, realtime):
    """The streaming benchmark: scenarios × strategies in virtual time (see docs/bench.md).

    Exits 1 if armctl's streamer drops a frame or misses a target anywhere."""
    if realtime:
        if scenario_names or size != "full" or jobs is not None:
            raise UsageFailure("--realtime runs its own jobs, one at a time: drop --scenario, --quick and --jobs")
        from ..bench.realtime import main as realtime_main

        sys.exit(realtime_main(lead_s, as_json))
    from ..bench.table import main as bench_main

    sys.exit(bench_main(size, scenario_names, lead_s, as_json, jobs))


_accept_output_flags_after(main)
