"""Properties of the whole command line, whatever the input: the contract of README and issue 10.

Strategy: the invariants are one function, ``check_outcome``: the exit code is documented
(0 ok, 1 problems in the input, 2 usage / unreadable), no traceback, and a failure says why
(on stderr; ``lint`` prints its findings on stdout).  Hypothesis drives ``armctl.ui.cli.main``
in-process (click's CliRunner) with inputs a user can type; a bounded sample of the same inputs
goes through the *installed* command in a fresh process (``sys.executable -m armctl``, always
with ``timeout=``), because a registry that fills on import passes in-process and fails for
users.  The inputs are derived from the package, not listed by hand, so that a new statement
word, rule code or numeric option inherits the properties:

- numbers near the float32 limits, subnormals, NaN, inf and huge integers in every word of every
  statement and in ``[expr]`` expressions, through lint / compile / estimate / run --dry-run,
  and float32 extremes inside frames given to ``decode``;
- every rule code (from ``armctl lint --list-rules --format json`` in a fresh process, and from
  the package's rule table) in ``--select`` / ``--ignore`` / armctl.toml; unknown codes → 2;
- every numeric option of every command (from click's command objects) given NaN, inf,
  negative or huge values → accepted, or exit 2 with a message naming the option.

Unbounded work and endless or changing inputs, which can hang, are in
tests/test_cli_properties_bounds.py (fresh processes only, each under a timeout).
"""

from __future__ import annotations

import importlib
import json
import math
import os
import pkgutil
import re
import resource
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from armctl.ui.cli import main
from cli_catalogue import QUICK_INVOCATIONS, VIRTUAL_SIM, all_commands, numeric_options, quick_args

EXIT_CODES = {0, 1, 2}  # 130 (Ctrl-C) and 141 (broken pipe) only where a test causes them
SUBPROCESS_TIMEOUT_S = 10.0
MEMORY_LIMIT_BYTES = 1 << 30  # far above what armctl needs for any input here (tens of MB)
PROPERTY_SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                                      HealthCheck.function_scoped_fixture])

F32_MAX = struct.unpack("<f", b"\xff\xff\x7f\x7f")[0]  # 3.4028234663852886e38
F32_MAX_TEXTS = (
    "3.4028235e38", "-3.4028235e38", "3.4028234663852886e38", "340282346638528859811704183484516925440",
    "-340282346638528859811704183484516925440", "3.4028236e38", "3.40282357e38", "3.4028234e38",
)
EDGE_NUMBER_TEXTS = (
    *F32_MAX_TEXTS, "1e38", "-1e38", "1e39", "-1e39", "1e308", "1e309", "-1e309", "1.7976931348623157e308",
    "1e-38", "1.17549435e-38", "1e-45", "1.4e-45", "-1.4e-45", "1e-300", "5e-324", "1e-400", "0", "-0", "0.0",
    "nan", "NaN", "-nan", "inf", "-inf", "Infinity", "9" * 40, "-" + "9" * 40, "1" + "0" * 400, "4294967296",
    "2147483648", "-2147483649", "18446744073709551616",
)

# One valid statement of each kind, after PRELUDE (which names everything a move needs).  Every
# word after the statement's name is a slot for a number; ``M3``'s number is one too.
PRELUDE = "G1 X200 Y0 Z150 A180 B0 C0 S1000 F3000\n"
STATEMENTS = (
    "G1 X200 Y0 Z150 A180 B0 C0 U0 V0 S1000 T1 F3000",
    "G220 X210 Y0 Z150 A180 B0 C0 U0 V0 K500 F3000",
    "G222 X200 Y0 Z150 A180 B0 C0 U0 V0 K500 F3000",
    "G230 X210 Y0 Z150 A180 B0 C0 U0 V0 K500 F3000 Q100",
    "G6 J1=0 J2=0 J3=0 J4=0 J5=90 J6=0 U0 V0 S1000 H0 F30",
    "G300 X210 Y10 Z150 A180 B0 C0 R75.25 F3000\nG301 X220 Y0 Z150 A180 B0 C0 F3000",
    "G4 P500",
    "M3",
    "G54 X0 Y0 Z0",
    "POSE 1",
    "PROGRAM 1",
    "MODE 0",
    "#<v> = 1\nG1 X[200 + #<v>] Y0 Z150 A180 B0 C0",
)
# a word: its letters (or "J1=" / "M" / "POSE ") then the number that fills the slot
_SLOT = re.compile(r"(?P<head>(?:J[1-6]=|#<v> = |(?:POSE|PROGRAM|MODE) |[A-Z]))(?P<value>-?[0-9.]+)(?=\s|$)")
STATEMENT_COMMANDS = (
    ("lint",), ("compile", "--format", "hex"), ("compile", "--format", "json"), ("estimate",), ("run", "--dry-run"),
)


def slots(text: str) -> list[re.Match]:
    """The numbers of a statement that a user could replace (not the G code itself)."""
    return [m for m in _SLOT.finditer(text) if not (m["head"] == "G" and m.start() in _line_starts(text))]


def _line_starts(text: str) -> set[int]:
    return {0} | {i + 1 for i, c in enumerate(text) if c == "\n"}


def fill(text: str, slot: re.Match, value: str) -> str:
    return text[: slot.start("value")] + value + text[slot.end("value"):]


def test_every_statement_template_is_valid_and_has_slots(workdir):
    """The generators below start from valid scripts, so every failure is the number's."""
    for statement in STATEMENTS:
        assert slots(statement), statement
        result = invoke(["compile", "--format", "hex", write(workdir, PRELUDE + statement + "\n")])
        assert result.exit_code == 0, (statement, result.output, result.stderr)


# --- the contract -------------------------------------------------------------------------------


def check_outcome(args, code: int, stdout: str, stderr: str, allowed=EXIT_CODES) -> None:
    where = f"armctl {' '.join(map(str, args))}"
    assert code in allowed, f"{where}: exit {code}, not one of {sorted(allowed)}\nstderr: {stderr[-2000:]}"
    assert "Traceback" not in stderr and "Traceback" not in stdout, f"{where}: a traceback\n{stderr[-3000:]}"
    if code != 0:
        said = stderr.strip() or (stdout.strip() if args and args[0] == "lint" and code == 1 else "")
        assert said, f"{where}: exit {code} with no message"


def invoke(args, input=None, env=None):
    """In process; an exception that escaped the command is a traceback for the user."""
    result = CliRunner().invoke(main, [str(a) for a in args], input=input, env=env, catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise AssertionError(f"armctl {' '.join(map(str, args))} raised {result.exception!r}") from result.exception
    return result


def check_in_process(args, input=None, allowed=EXIT_CODES, env=None):
    result = invoke(args, input=input, env=env)
    check_outcome(args, result.exit_code, result.stdout, result.stderr, allowed)
    return result


def fresh_env(**extra: str) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.startswith("ARMCTL_")}
    env.update(PYTHONIOENCODING="utf-8", COLUMNS="100", **extra)
    return env


def limit_memory() -> None:
    """In the child before exec: a runaway read ends in MemoryError, not in the machine swapping."""
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT_BYTES, MEMORY_LIMIT_BYTES))


def run_fresh(args, cwd: Path, input: bytes | None = None, timeout_s: float = SUBPROCESS_TIMEOUT_S,
              stdin=subprocess.DEVNULL) -> subprocess.CompletedProcess:
    """The installed command in a new interpreter; a hang fails the test, never the suite."""
    command = [sys.executable, "-m", "armctl", *map(str, args)]
    try:
        return subprocess.run(command, input=input, stdin=stdin if input is None else None, capture_output=True,
                              cwd=cwd, env=fresh_env(), timeout=timeout_s, preexec_fn=limit_memory)
    except subprocess.TimeoutExpired:
        pytest.fail(f"armctl {' '.join(map(str, args))}: no answer within {timeout_s} s (a hang)")


def check_fresh(args, cwd: Path, input: bytes | None = None, allowed=EXIT_CODES, stdin=subprocess.DEVNULL):
    done = run_fresh(args, cwd, input=input, stdin=stdin)
    stdout, stderr = (done.stdout.decode("utf-8", "replace"), done.stderr.decode("utf-8", "replace"))
    check_outcome(args, done.returncode, stdout, stderr, allowed)
    return done.returncode, stdout, stderr


def write(directory: Path, text: str, name: str = "job.txt") -> Path:
    path = directory / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """An empty directory with no armctl.toml above it, and no ARMCTL_* in the environment."""
    from armctl.host.profile import find_config

    monkeypatch.chdir(tmp_path)
    for name in [k for k in os.environ if k.startswith("ARMCTL_")]:
        monkeypatch.delenv(name)
    assert find_config(tmp_path)[0] is None, "an armctl.toml above the temporary directory"
    return tmp_path


# --- numbers near the float32 limits, NaN, inf, huge integers -----------------------------------


def _float_text(x: float) -> str:
    return repr(x) if math.isfinite(x) else str(x)


number_texts = st.one_of(
    st.sampled_from(F32_MAX_TEXTS),
    st.sampled_from(EDGE_NUMBER_TEXTS),
    st.floats(allow_nan=False, allow_infinity=False).map(_float_text),
    st.floats(width=32, allow_nan=False, allow_infinity=False).map(_float_text),
    st.floats(min_value=F32_MAX * 0.999999, max_value=F32_MAX * 1.000001).map(_float_text),
    st.integers(min_value=-(10**60), max_value=10**60).map(str),
)
# the same number inside an expression: alone, scaled, summed, negated, or a NaN made inside
expression_texts = st.builds(
    lambda form, n: form.format(n=n),
    st.sampled_from(("[{n}]", "[{n} * 10]", "[{n} / 3]", "[0 - {n}]", "[{n} + {n}]", "[{n} * 0]", "-[{n}]")),
    number_texts,
) | st.sampled_from(("[inf * 0]", "[1e38 * 1e38]", "[3.4028235e38 * 1.0000001]", "[1 / 0]", "[0 / 0]",
                     "[-3.4028235e38 - 1e32]"))


@st.composite
def scripts_with_one_edge_number(draw):
    statement = draw(st.sampled_from(STATEMENTS))
    slot = draw(st.sampled_from(slots(statement)))
    value = draw(number_texts | expression_texts)
    return PRELUDE + fill(statement, slot, value) + "\n"


@pytest.mark.parametrize("statement", STATEMENTS, ids=lambda s: s.split()[0])
def test_float32_max_in_every_word_of_every_statement(workdir, statement):
    """Exhaustive over the words (Hypothesis finds the exact-integer spelling of the float32
    maximum only now and then): every slot, every spelling, every command."""
    failures = []
    for slot in slots(statement):
        for value in F32_MAX_TEXTS:
            script = PRELUDE + fill(statement, slot, value) + "\n"
            path = write(workdir, script)
            for command in STATEMENT_COMMANDS:
                try:
                    check_in_process([*command, path])
                except AssertionError as error:
                    failures.append(f"{' '.join(command)} on {script.splitlines()[-1]!r}: {str(error).splitlines()[0]}")
    assert not failures, f"{len(failures)} failures, the first ones:\n" + "\n".join(failures[:8])


@settings(PROPERTY_SETTINGS, max_examples=200)
@given(script=scripts_with_one_edge_number(), command=st.sampled_from(STATEMENT_COMMANDS))
def test_an_edge_number_in_any_word_gives_a_documented_exit_and_no_traceback(workdir, script, command):
    path = write(workdir, script)
    result = check_in_process([*command, path])
    if result.exit_code == 1 and command[0] != "lint":
        assert re.search(r"job\.txt:\d+:\d+", result.stderr), f"the error is not located:\n{result.stderr}"


@settings(PROPERTY_SETTINGS, max_examples=100)
@given(script=scripts_with_one_edge_number())
def test_lint_clean_means_compile_and_dry_run_succeed(workdir, script):
    """What lint accepts, compile writes and run --dry-run checks: no second opinion later."""
    path = write(workdir, script)
    if check_in_process(["lint", path]).exit_code != 0:
        return
    for command in STATEMENT_COMMANDS[1:]:
        result = check_in_process([*command, path])
        assert result.exit_code == 0, f"lint passed {script!r} but {' '.join(command)} exits {result.exit_code}:\n" \
                                      f"{result.stderr}"


# the reproducers, through the installed command in a fresh process
FLOAT32_MAX_SCRIPTS = (
    PRELUDE + "G1 X201 S340282346638528859811704183484516925440\n",
    PRELUDE + "G1 X201 U340282346638528859811704183484516925440\n",
    PRELUDE + "G1 X201 A3.4028235e38\n",
    PRELUDE + "G1 X[3.4028235e38 * 0 + 200] Y[1e39]\n",
    "G4 P3e38\n",
    PRELUDE + "G1 U3e38\n",
)


@pytest.mark.parametrize("index", range(len(FLOAT32_MAX_SCRIPTS)))
def test_float32_extremes_in_process_and_through_the_installed_command(workdir, index):
    """Each reproducer through every command in process, and through one command in a fresh
    process (in turn: every command meets one there), where each pair was a process (30)."""
    path = write(workdir, FLOAT32_MAX_SCRIPTS[index])
    for command in STATEMENT_COMMANDS:
        result = check_in_process([*command, path])
        _located_unless_lint(command, result.exit_code, result.stderr)
    command = STATEMENT_COMMANDS[index % len(STATEMENT_COMMANDS)]
    code, _stdout, stderr = check_fresh([*command, path], workdir)
    _located_unless_lint(command, code, stderr)


def _located_unless_lint(command, code: int, stderr: str) -> None:
    if command[0] != "lint" and code == 1:
        assert re.search(r"job\.txt:\d+:\d+", stderr), stderr


# frames carrying float32 extremes, in each form decode reads
SPECIAL_F32 = (b"\xff\xff\x7f\x7f", b"\xff\xff\x7f\xff", b"\x00\x00\x80\x7f", b"\x00\x00\x80\xff",
               b"\x00\x00\xc0\x7f", b"\x01\x00\x00\x00", b"\xff\xff\x7f\x00", b"\x00\x00\x00\x80")


@st.composite
def frames_with_extreme_floats(draw):
    """A motion frame (head, command, slots, tail) or a status frame with extreme floats in it."""
    extreme = st.sampled_from(SPECIAL_F32) | st.binary(min_size=4, max_size=4)
    if draw(st.booleans()):
        command = draw(st.sampled_from(b"1234567"))
        body = b"".join(draw(extreme) for _ in range(11))
        return bytes([0xEE, command, draw(st.integers(0, 4))]) + body + b"\xef"
    return bytes([0xCE]) + draw(st.binary(min_size=1, max_size=1)) + draw(extreme) + draw(
        st.binary(min_size=2, max_size=2)) + b"\xcf"


@st.composite
def decode_inputs(draw):
    frames = draw(st.lists(frames_with_extreme_floats(), min_size=1, max_size=4))
    data = b"".join(frames)
    form = draw(st.sampled_from(("raw", "hex", "spaced hex", "log")))
    if form == "hex":
        return data.hex().encode()
    if form == "spaced hex":
        return " ".join(f"{b:02x}" for b in data).encode() + b"\n"
    if form == "log":
        return b"".join(json.dumps({"dir": "tx", "hex": f.hex()}).encode() + b"\n" for f in frames)
    return data


@PROPERTY_SETTINGS
@given(data=decode_inputs())
def test_decode_of_frames_carrying_float32_extremes(workdir, data):
    check_in_process(["decode", "-"], input=data)


@pytest.mark.parametrize("text", [b"ceffff7f7f000064cf\n", b"1 23 4\n", b"[" * 100_000 + b"\n",
                                  b'{"hex": ' * 10_000 + b"\n"], ids=["f32-max-status", "split-byte", "deep-json",
                                                                      "deep-json-object"])
def test_decode_reproducers_through_the_installed_command(tmp_path, text):
    check_fresh(["decode", "-"], tmp_path, input=text)


# --- rule codes in --select / --ignore ------------------------------------------------------------


def codes_from_the_package() -> list[str]:
    """The package's rule table, with every module of armctl.lint imported (any may register a rule)."""
    import armctl.lint
    from armctl.lint.registry import RULES

    for module in pkgutil.iter_modules(armctl.lint.__path__, "armctl.lint."):
        importlib.import_module(module.name)

    return list(RULES)


@pytest.fixture(scope="module")
def listed_codes(tmp_path_factory) -> list[str]:
    """What a user sees: --list-rules in a fresh process."""
    cwd = tmp_path_factory.mktemp("rules")
    done = run_fresh(["lint", "--list-rules", "--format", "json"], cwd)
    assert done.returncode == 0, done.stderr
    return [record["code"] for record in json.loads(done.stdout)]


def test_list_rules_in_a_fresh_process_shows_the_whole_table(listed_codes):
    package = codes_from_the_package()
    assert any(code.startswith("L") for code in package), "the package has lint rules"
    assert listed_codes == package


CLEAN_SCRIPT = PRELUDE + "G4 P100\n"


def _code_cases() -> list[str]:
    codes = codes_from_the_package()
    prefixes = sorted({code[:n] for code in codes for n in (1, 2, 3)})
    return [*codes, *prefixes, "ALL", "e", codes[-1].lower()]


@pytest.mark.parametrize("option", ["--select", "--ignore"])
def test_every_rule_code_and_prefix_is_accepted_in_process(workdir, option):
    path = write(workdir, CLEAN_SCRIPT)
    for code in _code_cases():
        result = check_in_process(["lint", option, code, path], allowed={0, 1})
        assert "unknown rule code" not in result.stderr, (code, result.stderr)


@pytest.mark.parametrize("option", ["--select", "--ignore"])
def test_every_listed_code_is_accepted_by_the_installed_command(tmp_path, listed_codes, option):
    """All codes in one fresh process (comma-separated), then each lint code on its own in one run
    of repeated options; the README's and --help's own examples too."""
    path = write(tmp_path, CLEAN_SCRIPT)
    lint_codes = [code for code in listed_codes if code.startswith("L")] or ["L103", "L203"]
    for args in ([option, ",".join(listed_codes)], [x for code in lint_codes for x in (option, code)],
                 [option, "L2"], [option, "E,L1"], [option, "L203"], [option, "L103"]):
        code, _stdout, stderr = check_fresh(["lint", *args, path], tmp_path, allowed={0, 1})
        assert "unknown rule code" not in stderr, (args, stderr)


def test_lint_ignore_in_armctl_toml_through_the_installed_command(tmp_path, listed_codes):
    path = write(tmp_path, CLEAN_SCRIPT)
    for codes in (["L203"], listed_codes):
        (tmp_path / "armctl.toml").write_text(f"[lint]\nignore = {json.dumps(codes)}\n", encoding="utf-8")
        code, _stdout, stderr = check_fresh(["lint", path], tmp_path, allowed={0, 1})
        assert "unknown rule code" not in stderr, (codes, stderr)


def _is_no_code_prefix(text: str) -> bool:
    entry = text.strip().upper()
    return bool(entry) and entry != "ALL" and not any(code.startswith(entry) for code in codes_from_the_package())


unknown_codes = st.text(alphabet="ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-.",
                        min_size=1, max_size=8).filter(_is_no_code_prefix)


@PROPERTY_SETTINGS
@given(unknown=unknown_codes, option=st.sampled_from(["--select", "--ignore"]),
       known=st.sampled_from(["", "E001,", "L,"]))
def test_an_unknown_code_is_a_usage_error_naming_it(workdir, unknown, option, known):
    path = write(workdir, CLEAN_SCRIPT)
    result = check_in_process(["lint", option, known + unknown, path], allowed={2})
    assert unknown in result.stderr, result.stderr


def test_an_unknown_code_through_the_installed_command(tmp_path):
    path = write(tmp_path, CLEAN_SCRIPT)
    for option in ("--select", "--ignore"):
        _code, _stdout, stderr = check_fresh(["lint", option, "Q999", path], tmp_path, allowed={2})
        assert "Q999" in stderr


# --- every numeric option of every command --------------------------------------------------------


TINY_SCRIPT = "G4 P10\n"
MUST_REJECT = ("nan", "inf", "-inf")
MAY_ACCEPT = ("-1", "1e39", "99999999999999999999999")


NUMERIC_OPTIONS = [
    (path, param.opts[-1] if param.opts[-1].startswith("--") else param.opts[0]) for path, param in numeric_options()
]


def test_every_command_has_a_quick_invocation():
    missing = [" ".join(path) for path, _command in all_commands() if path[0] not in QUICK_INVOCATIONS]
    assert not missing, f"add these to QUICK_INVOCATIONS: {missing}"
    assert len(NUMERIC_OPTIONS) >= 8, NUMERIC_OPTIONS  # the walk over click's objects found them


def _with_option(path, option, value, script: Path) -> list[str]:
    return [*quick_args(path, script), f"{option}={value}"]


# Through the installed command: one value each option must refuse and one it may accept (a fresh
# process per value repeated what the in-process run proves: 132 processes, 14 s of CPU a suite).
FRESH_VALUES = ("nan", "99999999999999999999999")


@pytest.mark.parametrize("path, option", NUMERIC_OPTIONS, ids=[f"{' '.join(p)} {o}" for p, o in NUMERIC_OPTIONS])
def test_a_numeric_option_rejects_nan_inf_and_accepts_or_rejects_the_rest_clearly(workdir, path, option):
    """Every value in process, and ``FRESH_VALUES`` through the installed command, where an
    accepted NaN that waits for ever fails at the subprocess's timeout."""
    script = write(workdir, TINY_SCRIPT)
    for fresh, values in ((False, (*MUST_REJECT, *MAY_ACCEPT)), (True, FRESH_VALUES)):
        without_option = None
        for value in values:
            args = _with_option(path, option, value, script)
            code, stderr = _numeric_outcome(args, fresh, workdir, {0, 1, 2} - ({0, 1} if value in MUST_REJECT else set()))
            if code == 2 and option not in stderr:
                # accepted, and the command failed for a reason of its own (jog needs a terminal):
                # then it fails the same way without the option
                if without_option is None:
                    without_option = _numeric_outcome(args[:-1], fresh, workdir, EXIT_CODES)
                assert value not in MUST_REJECT and (code, stderr) == without_option, (
                    f"armctl {' '.join(args)}: exit 2 and the message does not name {option}:\n{stderr}")


def _numeric_outcome(args, fresh: bool, cwd: Path, allowed) -> tuple[int, str]:
    if fresh:
        code, _stdout, stderr = check_fresh(args, cwd, input=b"", allowed=allowed)
        return code, stderr
    result = check_in_process(args, input=b"", allowed=allowed)
    return result.exit_code, result.stderr
