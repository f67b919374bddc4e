"""Review 6, hostile inputs: what a fresh ``armctl`` process did with inputs that crashed it.

Each case ran through the installed command, in a fresh process, with a timeout:

- a port (``--port``, ``ARMCTL_PORT``, a ``sim://`` profile path) holding bytes that are not
  UTF-8 (a file name such as ``p\\xff.toml`` is legal on Linux) died of UnicodeEncodeError in
  the calibration store's file name (``urllib.parse.quote`` of the arm's identity): a traceback,
  exit 1, on ``status``, ``config``, ``estimate``, ``probe --forget`` …;
- ``armctl --help`` and ``armctl --version`` into a full device (``> /dev/full``) died of
  OSError (traceback, exit 1), and into a pipe whose reader had gone exited 1, not 141:
  the group's own options run before any command, outside the handler that maps errors to
  exit codes.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ARMCTL = str(Path(sys.executable).with_name("armctl"))
TIMEOUT_S = 60
VIRTUAL = "sim://?clock=virtual"
NOT_UTF8 = os.fsdecode(b"\xff")  # the byte 0xff in a file name, as Python hands it over (a surrogate)


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    return {**env, **extra}


def _armctl(args, cwd, env=None, timeout=TIMEOUT_S) -> subprocess.CompletedProcess:
    return subprocess.run([ARMCTL, *args], capture_output=True, timeout=timeout, cwd=cwd,
                          env=env or _env(), stdin=subprocess.DEVNULL)


def _armctl_fresh_or_here(args, cwd, monkeypatch, fresh: bool, **extra_env: str):
    """``armctl ARGS`` in ``cwd``: the installed command in a fresh process (``fresh``), else in this
    process (click's runner; the same exit code and stderr, for a matrix's other cases at a
    fraction of a process's start-up)."""
    if fresh:
        return _armctl(args, cwd, _env(**extra_env))
    from click.testing import CliRunner

    from armctl.ui.cli import main

    monkeypatch.chdir(cwd)
    result = CliRunner().invoke(main, args, env={"ARMCTL_PORT": None, **extra_env})
    return subprocess.CompletedProcess(args, result.exit_code, result.stdout_bytes, result.stderr_bytes)


def _no_traceback(done: subprocess.CompletedProcess) -> str:
    stderr = done.stderr.decode("utf-8", "replace")
    assert "Traceback" not in stderr, stderr
    return stderr


@pytest.fixture
def workdir(tmp_path):
    shutil.copy(ROOT / "scripts" / "pick_and_place.txt", tmp_path / "job.txt")
    shutil.copy(ROOT / "armctl" / "data" / "default_profile.toml", tmp_path / f"p{NOT_UTF8}.toml")
    return tmp_path


@pytest.mark.timeout(120)
@pytest.mark.parametrize("args, expected", [
    (["status", "--once", "--port", f"/dev/tty{NOT_UTF8}"], 1),  # no such device, as any missing one
    (["config", "--port", f"/dev/tty{NOT_UTF8}"], 0),
    (["estimate", "job.txt"], 0),  # with ARMCTL_PORT below
    (["run", "job.txt", "--dry-run", "--port", f"/dev/tty{NOT_UTF8}"], 0),
    (["probe", "--forget", f"/dev/tty{NOT_UTF8}"], 1),  # nothing kept for it
    (["status", "--once", "--port", f"socket://{NOT_UTF8}:1"], 1),  # no such host
    (["status", "--once", "--port", f"{VIRTUAL}&profile=p{NOT_UTF8}.toml"], 0),  # the file is there
    (["status", "--once", "--port", f"{VIRTUAL}&profile=none{NOT_UTF8}.toml"], 2),  # it is not
    (["probe", "--no-motion", "--port", f"{VIRTUAL}&fifo=50&profile=p{NOT_UTF8}.toml"], 0),  # and keeps it
], ids=lambda value: repr(value) if isinstance(value, list) else str(value))
def test_a_port_with_bytes_that_are_not_utf8(workdir, tmp_path, args, expected):
    env = _env(XDG_DATA_HOME=str(tmp_path / "data"))
    if args[0] == "estimate":
        env["ARMCTL_PORT"] = f"/dev/tty{NOT_UTF8}"
    done = _armctl(args, workdir, env)
    stderr = _no_traceback(done)
    assert done.returncode == expected, stderr
    if expected:
        assert stderr.rstrip().splitlines()[-1].startswith(("armctl: ", "nothing stored for device /dev/tty")), stderr


@pytest.mark.parametrize("args", [["--help"], ["--version"], ["-h"]], ids=" ".join)
def test_the_groups_own_options_into_a_full_device(tmp_path, args):
    with open("/dev/full", "w") as full:
        done = subprocess.run([ARMCTL, *args], stdout=full, stderr=subprocess.PIPE, timeout=TIMEOUT_S, cwd=tmp_path,
                              env=_env(), stdin=subprocess.DEVNULL)
    stderr = _no_traceback(done)
    assert done.returncode == 2, stderr
    assert stderr.strip() == "armctl: No space left on device", stderr  # (as `armctl run --help > /dev/full`)


@pytest.mark.parametrize("args", [["--help"], ["--version"], ["run", "--help"]], ids=" ".join)
def test_the_groups_own_options_into_a_pipe_nobody_reads(tmp_path, args):
    read, write = os.pipe()
    os.close(read)  # the reader went away before armctl wrote a byte (`| head -c0`)
    try:
        done = subprocess.run([ARMCTL, *args], stdout=write, stderr=subprocess.PIPE, timeout=TIMEOUT_S, cwd=tmp_path,
                              env=_env(), stdin=subprocess.DEVNULL)
    finally:
        os.close(write)
    stderr = _no_traceback(done)
    assert done.returncode == 141 and not stderr.strip(), stderr


# --- an armctl.toml that is not a regular file ----------------------------------------------------
# Found by name only where it is a regular file (``Path.is_file``): a dangling symbolic link (a
# config linked to a file since moved), a link loop, a named pipe, a directory, a link to a
# device were passed over as if there were no armctl.toml — the search went on to the parent
# directory's, or to none — so the file's port, baud, [connector] (a measured FIFO of 50 frames)
# and [lint] silently did not apply: exit 0 on every command.  Now each is refused as a profile
# named by one is (exit 2, naming the file), before it is opened: a named pipe is never waited on.

_NOT_A_FILE = {
    "a dangling symbolic link": lambda path: path.symlink_to(path.parent / "moved-away.toml"),
    "a symbolic link loop": lambda path: path.symlink_to(path),
    "a named pipe": lambda path: os.mkfifo(path),
    "a directory": lambda path: path.mkdir(),
    "a link to /dev/zero": lambda path: path.symlink_to("/dev/zero"),
}


@pytest.mark.parametrize("where", ["project", "user"])
@pytest.mark.parametrize("kind", list(_NOT_A_FILE))
@pytest.mark.parametrize("args", [["config"], ["estimate", "job.txt"], ["status", "--once", "--port", VIRTUAL]],
                         ids=" ".join)
def test_an_armctl_toml_that_is_not_a_regular_file_is_refused(workdir, tmp_path, monkeypatch, args, kind, where):
    project = workdir / "project"
    project.mkdir()
    shutil.copy(workdir / "job.txt", project / "job.txt")
    # what the search found instead: a parent's armctl.toml (project), none (user)
    (workdir / "armctl.toml").write_text('[connector]\nfifo_frames = 200\n')
    user_folder = tmp_path / "config" / "armctl"
    user_folder.mkdir(parents=True)
    path = (project if where == "project" else user_folder) / "armctl.toml"
    _NOT_A_FILE[kind](path)
    fresh = args == ["config"] and where == "project"  # the others in this process
    done = _armctl_fresh_or_here(args, project, monkeypatch, fresh, XDG_CONFIG_HOME=str(tmp_path / "config"))
    stderr = _no_traceback(done)
    assert done.returncode == 2, stderr
    assert stderr.strip().splitlines()[-1].startswith(f"armctl: {path}"), stderr


# --- a port URL's scheme --------------------------------------------------------------------------
# pyserial reads a URL's scheme in any case (``SIM://`` is its sim:// handler), armctl only in
# lower case: ``--port 'SIM://?clock=virtual'`` ran the simulator without its banner and without
# its own FIFO size as proof, so the pick-and-place job ended "finished, unproven" (exit 1) where
# ``sim://`` ends "finished" (exit 0).  And a scheme no handler takes (``http://``, `` sim://``)
# passed ``armctl config`` (exit 0) while every command that opens the port refused it.


@pytest.mark.parametrize("scheme", ["SIM", "Sim"])
def test_a_sim_url_in_capitals_is_the_simulator(workdir, scheme):
    done = _armctl(["run", "job.txt", "--no-live", "--port", f"{scheme}://?clock=virtual"], workdir)
    stderr = _no_traceback(done)
    assert done.returncode == 0, stderr
    assert "armctl: using the built-in simulator (sim://?clock=virtual)" in stderr, stderr
    assert "finished: the arm finished the job" in (done.stdout.decode() + stderr), stderr


@pytest.mark.parametrize("args", [["config"], ["status", "--once"], ["run", "job.txt", "--no-live"]], ids=" ".join)
@pytest.mark.parametrize("port", ["http://arm.local", " sim://", "bogus://x"])
def test_a_port_of_a_scheme_no_handler_takes_is_a_configuration_error(workdir, monkeypatch, args, port):
    done = _armctl_fresh_or_here(args, workdir, monkeypatch, port == " sim://", ARMCTL_PORT=port)
    stderr = _no_traceback(done)
    assert done.returncode == 2, stderr
    scheme = port.split("://")[0]
    assert stderr.strip().splitlines()[-1].startswith(f"armctl: ARMCTL_PORT: {port!r}: no port type {scheme!r}"), stderr


# --- probe --forget '' ----------------------------------------------------------------------------
# ``--forget`` alone forgets the arm on the port; ``--forget ''`` (``--forget "$ARM"`` with ARM
# unset) was read as the same, and forgot the configured arm's calibration without a word of
# doubt, exit 0 — where ``--port ''`` is refused as naming no port.


@pytest.mark.timeout(120)
def test_probe_forget_of_an_empty_name_forgets_nothing(tmp_path):
    arm = f"{VIRTUAL}&fifo=50"
    env = _env(XDG_DATA_HOME=str(tmp_path / "data"), ARMCTL_PORT=arm)
    assert _armctl(["probe", "--no-motion", "--json"], tmp_path, env).returncode == 0
    done = _armctl(["probe", "--forget", ""], tmp_path, env)
    stderr = _no_traceback(done)
    assert done.returncode == 2, stderr
    assert "--forget '' names no arm" in stderr, stderr
    assert "fifo_frames=50" in _armctl(["probe", "--list"], tmp_path, env).stdout.decode()  # still kept
    done = _armctl(["probe", "--forget"], tmp_path, env)  # alone: the arm on the port, as before
    assert done.returncode == 0 and b"forgot the calibration of sim://?fifo_frames=50" in done.stdout, done.stderr


# --- an output option given an empty name ---------------------------------------------------------
# ``--log "$LOG"`` with LOG unset: ``run --log ''`` ran the job without its journal (exit 0: no
# resume possible after a crash), ``probe --write ''`` wrote no armctl.toml, ``plot -o ''`` wrote
# JOB.html, ``sim --pty --stats ''`` served until Ctrl-C and failed only then — each as if the
# option had been left out.  Now an empty or blank name is a usage error naming the option, before
# anything is read, opened or sent.

_EMPTY_OUTPUT = {
    "run --log": ["run", "job.txt", "--no-live", "--port", VIRTUAL, "--log", ""],
    "probe --write": ["probe", "--no-motion", "--port", VIRTUAL, "--write", " "],
    "plot -o": ["plot", "job.txt", "-o", ""],
    "compile -o": ["compile", "job.txt", "-o", ""],
    "sim --stats": ["sim", "--pty", "--stats", ""],
    "jog --record": ["jog", "--port", "sim://", "--record", ""],
}


@pytest.mark.timeout(40)
@pytest.mark.parametrize("name", list(_EMPTY_OUTPUT))
def test_an_output_option_naming_no_file_is_a_usage_error(workdir, name):
    _refused_at_once(_EMPTY_OUTPUT[name], name, "names no file: give a path", workdir)


def _refused_at_once(args, name: str, said: str, workdir) -> None:
    """``args`` end at once in a usage error naming the option of ``name`` ("run --log"), saying
    ``said``, with nothing written: not the option left out, not a file made."""
    try:
        done = _armctl(args, workdir, timeout=15)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{' '.join(args)}: ran on as if the option were left out")
    stderr = _no_traceback(done)
    assert done.returncode == 2, stderr
    option = name.split()[1]
    assert f"Invalid value for '{option}" in stderr and said in stderr, stderr
    assert not done.stdout and sorted(p.name for p in workdir.iterdir()) == ["job.txt", f"p{NOT_UTF8}.toml"]


# --- probe --write through a symbolic link, or into no directory ----------------------------------
# ``probe --write linked.toml`` (a link to a shared armctl.toml) replaced the link with a regular
# file (a temporary file renamed over the link's own name): the shared file never got the values,
# and the link was gone.  ``--write nodir/armctl.toml`` probed the arm, then failed naming a
# temporary file nobody asked for (``nodir/.armctl.toml.probe-tmp``).


@pytest.mark.timeout(120)
def test_probe_write_through_a_symbolic_link_writes_its_target(tmp_path):
    shared = tmp_path / "shared" / "armctl.toml"
    shared.parent.mkdir()
    shared.write_text('# the team\'s config\n[lint]\nignore = ["L203"]\n')
    shared.chmod(0o640)
    (tmp_path / "armctl.toml").symlink_to(shared)
    done = _armctl(["probe", "--no-motion", "--port", f"{VIRTUAL}&fifo=60", "--write", "armctl.toml"], tmp_path,
                   _env(XDG_DATA_HOME=str(tmp_path / "data")))
    assert done.returncode == 0, _no_traceback(done)
    assert (tmp_path / "armctl.toml").is_symlink()
    text = shared.read_text()
    assert text.startswith('# the team\'s config\n[lint]\nignore = ["L203"]\n') and "fifo_frames = 60" in text, text
    assert shared.stat().st_mode & 0o777 == 0o640
    assert sorted(p.name for p in shared.parent.iterdir()) == ["armctl.toml"]  # no temporary file left


def test_probe_write_into_a_missing_directory_is_refused_before_the_probe(tmp_path):
    done = _armctl(["probe", "--no-motion", "--port", VIRTUAL, "--write", "nodir/armctl.toml"], tmp_path,
                   _env(XDG_DATA_HOME=str(tmp_path / "data")))
    stderr = _no_traceback(done)
    assert done.returncode == 2, stderr
    assert stderr.strip().splitlines()[-1] == ("Error: Invalid value for '--write': cannot write nodir/armctl.toml: "
                                               "No such file or directory (no directory nodir)"), stderr
    assert not done.stdout and not (tmp_path / "data").exists()  # nothing probed, nothing kept


# --- compile -o on a full device names it ---------------------------------------------------------
# ``compile -o /dev/full`` said "armctl: No space left on device": which output, of the command's
# two (the file and stdout), went unsaid, where the module's rule is that errors carry the path given.


@pytest.mark.parametrize("fmt", ["hex", "bin", "json"])
def test_compile_into_a_full_device_names_it(workdir, fmt):
    done = _armctl(["compile", "job.txt", "--format", fmt, "-o", "/dev/full"], workdir)
    stderr = _no_traceback(done)
    assert done.returncode == 2, stderr
    assert stderr.strip() == "armctl: /dev/full: No space left on device", stderr


# --- a sim:// profile that the simulator refuses --------------------------------------------------
# ``armctl config --port 'sim://?profile=bad.toml'`` listed the port (exit 0) while every command
# that opens it refused the profile (exit 2): the simulator read it only as the port opened.  It is
# read where the URL is checked now, as ``sim --url`` reads it, and the message names the origin.

_BAD_SIM_PROFILES = {
    "missing": None,
    "a directory": "dir",
    "not UTF-8": b"name = \"\xff\"\n",
    "a limit upside down": b"[joints]\nj1_deg = [170.0, -170.0]\n",
}


@pytest.mark.parametrize("kind", list(_BAD_SIM_PROFILES))
@pytest.mark.parametrize("args", [["config"], ["status", "--once"]], ids=" ".join)
def test_a_sim_profile_the_simulator_refuses_is_refused_by_config_too(tmp_path, kind, args):
    content = _BAD_SIM_PROFILES[kind]
    if content == "dir":
        (tmp_path / "sim.toml").mkdir()
    elif content is not None:
        (tmp_path / "sim.toml").write_bytes(content)
    done = _armctl([*args, "--port", f"{VIRTUAL}&profile=sim.toml"], tmp_path)
    stderr = _no_traceback(done)
    assert done.returncode == 2, stderr
    assert stderr.strip().splitlines()[-1].startswith("armctl: --port: sim:// option profile: sim.toml"), stderr


# --- a NUL in armctl.toml's port -----------------------------------------------------------------
# TOML can hold a NUL (``port = "/dev/ttyUSB0\u0000"``), a command line or the environment cannot:
# armctl config listed it (exit 0) and every command failed on opening, "cannot open /dev/ttyUSB0:
# embedded null byte" (exit 1), naming a port that is not the one written.  A profile path with a
# NUL was refused already; the port is refused the same way, naming the file.


@pytest.mark.parametrize("port", ["/dev/ttyUSB0\\u0000", "socket://\\u0000:1", "loop://\\u0000"])
@pytest.mark.parametrize("args", [["config"], ["status", "--once"], ["run", "job.txt", "--no-live"]], ids=" ".join)
def test_a_nul_in_the_port_of_armctl_toml_is_refused(workdir, monkeypatch, port, args):
    (workdir / "armctl.toml").write_text(f'port = "{port}"\n')
    done = _armctl_fresh_or_here(args, workdir, monkeypatch, port.startswith("/dev/"))
    stderr = _no_traceback(done)
    assert done.returncode == 2, stderr
    assert stderr.strip().splitlines()[-1].startswith(f"armctl: {workdir / 'armctl.toml'}: port = "), stderr
    assert "NUL" in stderr, stderr


# --- a port path that names no device -------------------------------------------------------------
# ``--port job.txt`` said "cannot open job.txt: Could not configure port: (25, 'Inappropriate ioctl
# for device')", ``--port adir`` "[Errno 21] could not open port adir: [Errno 21] Is a directory:
# 'adir'": pyserial's words, after opening a regular file read-write.  Now it is said what the path
# is, before anything is opened (exit 1, as any port that cannot be opened).

_NOT_A_DEVICE = {"job.txt": "a regular file", "adir": "a directory", "fifo": "a named pipe"}


@pytest.mark.parametrize("path", list(_NOT_A_DEVICE))
def test_a_port_that_is_no_device_is_named_for_what_it_is(workdir, path):
    (workdir / "adir").mkdir()
    os.mkfifo(workdir / "fifo")
    before = (workdir / "job.txt").stat().st_mtime_ns
    done = _armctl(["status", "--once", "--port", path], workdir)
    stderr = _no_traceback(done)
    assert done.returncode == 1, stderr
    assert stderr.strip() == (f"armctl: {path} is {_NOT_A_DEVICE[path]}, not a serial device: give the arm's port "
                              "(`armctl ports` lists the ports found)"), stderr
    assert (workdir / "job.txt").stat().st_mtime_ns == before


# --- a port with a space at its end ----------------------------------------------------------------
# ``ARMCTL_PORT="/dev/ttyUSB0 "`` (a copied line): "no such device: /dev/ttyUSB0  (is the arm
# plugged in? …)" — the one character at fault cannot be seen.  A port name with a space at
# either end is quoted in the message.


@pytest.mark.parametrize("port", ["/dev/ttyUSB9 ", " /dev/ttyUSB9", "/dev/ttyUSB9\t"])
def test_a_port_name_with_space_at_an_end_is_quoted(tmp_path, port):
    done = _armctl(["status", "--once"], tmp_path, _env(ARMCTL_PORT=port))
    stderr = _no_traceback(done)
    assert done.returncode == 1, stderr
    assert stderr.strip().startswith(f"armctl: no such device: {port!r} (is the arm plugged in?"), stderr


# --- "-" as an output ------------------------------------------------------------------------------
# "-" is standard input for a script; as an output it made a file named "-": ``compile -o -``
# printed nothing and exited 0 (the frames in ./-), ``run --log -`` journalled to ./-.  Now
# ``compile -o -`` is standard output (the frames printed, as without -o), and any other output
# option refuses "-" (exit 2, before anything is read or sent): ./- names such a file.

_DASH_OUTPUT = {name: [*args[:-1], "-"] for name, args in _EMPTY_OUTPUT.items() if name != "compile -o"}


def test_compile_o_dash_is_standard_output(workdir):
    done = _armctl(["compile", "job.txt", "-o", "-"], workdir)
    assert done.returncode == 0, _no_traceback(done)
    assert done.stdout == _armctl(["compile", "job.txt"], workdir).stdout and done.stdout.count(b"\n") == 14
    assert not (workdir / "-").exists()


@pytest.mark.timeout(40)
@pytest.mark.parametrize("name", list(_DASH_OUTPUT))
def test_an_output_option_refuses_a_dash(workdir, name):
    _refused_at_once(_DASH_OUTPUT[name], name, "'-' names no file here: write ./- for a file named -", workdir)


# --- lint of a tree with a directory it cannot read ------------------------------------------------
# ``armctl lint scripts`` with scripts/old unreadable (mode 000, another user's) said "All checks
# passed (1 file checked)", exit 0: os.walk passes over a directory it cannot list, so the scripts
# in it went unchecked with nothing said — in CI, a green check.  A path that cannot be read is exit
# 2 (README); now so is a directory below one named, reported in order, the rest still linted.

def _without_root_powers() -> list[str]:
    """A prefix that runs a command without root's power to read anything (CAP_DAC_OVERRIDE)."""
    if os.geteuid() != 0:
        return []
    if shutil.which("setpriv") is None:
        pytest.skip("running as root without setpriv: a mode-000 directory is readable")
    caps = "-dac_override,-dac_read_search"
    return ["setpriv", "--bounding-set", caps, "--inh-caps", caps]


def test_lint_reports_a_directory_it_cannot_read(tmp_path):
    tree = tmp_path / "scripts"
    (tree / "old").mkdir(parents=True)
    shutil.copy(ROOT / "scripts" / "pick_and_place.txt", tree / "job.txt")
    (tree / "old" / "bad.txt").write_text("G1 X\n")
    (tree / "old").chmod(0)
    try:
        done = subprocess.run([*_without_root_powers(), ARMCTL, "lint", "scripts"], capture_output=True, text=True,
                              timeout=TIMEOUT_S, cwd=tmp_path, env=_env(), stdin=subprocess.DEVNULL)
    finally:
        (tree / "old").chmod(0o755)
    assert "Traceback" not in done.stderr
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert "armctl lint: cannot read scripts/old: Permission denied" in done.stderr, done.stderr
    assert "1 path could not be read" in done.stdout + done.stderr, (done.stdout, done.stderr)


# --- armctl move to a target the profile finds out of reach -----------------------------------------
# ``armctl move x=0 y=0 z=0``: lint's L103 warning (the pose needs J2 = 122°, outside its limits)
# went to a logger shown only with -v; the user read only the end — "frames may have been lost ...
# fifo_frames = 200 ... looks wrong ... probe it" — for a target the check knew to be out of reach.
# ``armctl run`` prints its script's warnings; ``move`` and ``home`` print theirs now too (not with -q).


@pytest.mark.parametrize("quiet", [False, True])
def test_move_prints_the_warning_of_its_line(tmp_path, quiet):
    done = _armctl([*(["-q"] if quiet else []), "move", "x=0", "y=0", "z=0", "--port", VIRTUAL], tmp_path)
    stderr = _no_traceback(done)
    assert done.returncode == 1, stderr
    assert ("L103 target (0, 0, 0)" in stderr) is not quiet, stderr
    assert b"frames may have been lost" in done.stdout  # (the summary: the arm refused the target)


# --- an output in a directory that is not there ---------------------------------------------------------
# ``sim --pty --stats nodir/stats.json`` served the arm until Ctrl-C, then failed to write what it
# had counted ("armctl: nodir/stats.json: No such file or directory", exit 2): the whole session's
# statistics lost.  Every output option now refuses a file in a missing directory before anything
# starts, naming both.


@pytest.mark.timeout(40)
def test_sim_stats_in_a_missing_directory_is_refused_at_once(workdir):
    _refused_at_once(["sim", "--pty", "--stats", "nodir/stats.json"], "sim --stats",
                     "cannot write nodir/stats.json: No such file or directory (no directory nodir)", workdir)


# --- decode: where hex text stops being hex ------------------------------------------------------------
# Hex text longer than 64 KiB that stops being hex is exit 2 (README): the message named the
# byte's offset in the file ("not hex text: byte 145509 is b'z'") where every other input error
# names FILE:LINE:COLUMN — one frame per line, the line is what a user opens.


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
def test_decode_names_the_line_and_column_where_hex_text_stops(tmp_path, newline):
    frame = "ee310100007a430000f0c20000164300003443000000000000000000007a4400000000000000000000000000803b45ef"
    lines = [frame] * 2000
    lines[1499] = frame[:4] + "zz" + frame[6:]
    (tmp_path / "frames.hex").write_text(newline.join(lines) + newline, newline="")
    done = _armctl(["decode", "frames.hex"], tmp_path)
    stderr = _no_traceback(done)
    assert done.returncode == 2, stderr
    assert stderr.strip().splitlines()[-1] == "armctl: frames.hex:1500:5: not hex text: 'z'", stderr


# --- decode: a log's names printed raw to the terminal -----------------------------------------------
# A log's job record names its script, port and arm; decode printed them as they were, so a log
# from elsewhere (a record's CRC is no signature) could send control sequences to the user's
# terminal — retitle it, clear it, recolour what follows.  Control characters are shown escaped.


def test_decode_shows_control_characters_of_a_log_escaped(tmp_path):
    record = {"t": 0, "dir": "job", "format": 1, "script": "job\x1b]0;owned\x07.txt", "from_line": 1,
              "port": "/dev/ttyUSB0\x1b[2J", "arm": "usb \x9b31m"}
    (tmp_path / "job.log").write_text(json.dumps(record) + "\n")
    done = _armctl(["decode", "job.log"], tmp_path)
    stderr = _no_traceback(done)
    assert done.returncode == 0, stderr
    assert not any(char in stderr for char in "\x1b\x07\x9b"), repr(stderr)
    assert "job.log:1: job job\\x1b]0;owned\\x07.txt from line 1 on port /dev/ttyUSB0\\x1b[2J (usb \\x9b31m)" in stderr
