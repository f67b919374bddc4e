"""Review 7's faults of armctl's inputs, each through the installed command in a fresh process and
in-process: (1) a malformed shell-completion request is one line and exit 2, never click's
traceback; (2) a TOML syntax error leads with FILE:LINE:COLUMN; (3) `armctl config` escapes the
control characters of a profile's name; (4) a ``sim://?profile=FILE`` is read once, so the
profile checked is the profile the simulator runs.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main

# The console script pip installed beside this interpreter: what a user runs.
INSTALLED = Path(sys.executable).with_name("armctl")
TIMEOUT_S = 30


def installed(*args: str, env: dict | None = None, cwd: Path) -> subprocess.CompletedProcess:
    assert INSTALLED.exists(), f"the armctl command is not installed beside {sys.executable}"
    base = {k: v for k, v in os.environ.items()
            if not k.endswith("_COMPLETE") and not k.startswith("COMP_") and k != "ARMCTL_PORT"}
    return subprocess.run([str(INSTALLED), *args], capture_output=True, text=True, cwd=cwd,
                          env={**base, **(env or {})}, timeout=TIMEOUT_S)


def one_line(stderr: str) -> str:
    assert "Traceback" not in stderr, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    return lines[0]


# --- 1. click's shell completion, asked with a malformed environment ------------------------------

MALFORMED = {  # the request → what the one line must name
    "bash, COMP_CWORD not a number": ({"_ARMCTL_COMPLETE": "bash_complete", "COMP_WORDS": "armctl ru",
                                        "COMP_CWORD": "abc"}, "COMP_CWORD='abc'"),
    "zsh, COMP_CWORD empty": ({"_ARMCTL_COMPLETE": "zsh_complete", "COMP_WORDS": "armctl ru", "COMP_CWORD": ""},
                              "COMP_CWORD=''"),
    "powershell, COMP_CWORD a float": ({"_ARMCTL_COMPLETE": "powershell_complete", "COMP_WORDS": "armctl ru",
                                        "COMP_CWORD": "1.5"}, "COMP_CWORD='1.5'"),
    "bash, an escape sequence as COMP_CWORD": ({"_ARMCTL_COMPLETE": "bash_complete", "COMP_WORDS": "armctl ru",
                                                "COMP_CWORD": "\x1b[2J"}, r"COMP_CWORD='\x1b[2J'"),
    "bash, COMP_CWORD unset": ({"_ARMCTL_COMPLETE": "bash_complete", "COMP_WORDS": "armctl ru"},
                               "COMP_CWORD is not set"),
    "zsh, COMP_WORDS unset": ({"_ARMCTL_COMPLETE": "zsh_complete", "COMP_CWORD": "1"}, "COMP_WORDS is not set"),
    "fish, COMP_CWORD unset": ({"_ARMCTL_COMPLETE": "fish_complete", "COMP_WORDS": "armctl ru"},
                               "COMP_CWORD is not set"),
    "fish, COMP_CWORD blank": ({"_ARMCTL_COMPLETE": "fish_complete", "COMP_WORDS": "armctl ru", "COMP_CWORD": " "},
                               "COMP_CWORD=' '"),
}


@pytest.mark.parametrize("case", MALFORMED)
def test_a_malformed_completion_request_is_one_line_and_exit_2(case, tmp_path):
    env, named = MALFORMED[case]
    done = installed(env=env, cwd=tmp_path)
    line = one_line(done.stderr)
    assert done.returncode == 2, done.stderr
    assert line.startswith("armctl: shell completion: ") and named in line, line
    assert "\x1b" not in line and done.stdout == ""


def test_a_word_that_is_not_utf8_is_one_line_and_exit_2(tmp_path):
    # a file name's bytes that are not UTF-8 (bash hands them over as they are): click's answer
    # for a path option echoes the word, and cannot encode it
    env = {"_ARMCTL_COMPLETE": "bash_complete", "COMP_WORDS": "armctl run --log \udcff", "COMP_CWORD": "3"}
    done = installed(env={k: os.fsencode(v) for k, v in env.items()}, cwd=tmp_path)
    line = one_line(done.stderr)
    assert done.returncode == 2 and line.startswith("armctl: shell completion: ") and "UTF-8" in line, line


def test_in_process_a_malformed_request_is_exit_2(monkeypatch):
    for name, value in {"_ARMCTL_COMPLETE": "bash_complete", "COMP_WORDS": "armctl ru", "COMP_CWORD": "abc"}.items():
        monkeypatch.setenv(name, value)
    result = CliRunner().invoke(main, [], prog_name="armctl")
    assert result.exit_code == 2 and "COMP_CWORD='abc'" in result.output, (result.exception, result.output)


@pytest.mark.parametrize("shell, cword, answer", [("bash", "1", "plain,run"), ("zsh", "1", "plain\nrun\n"),
                                                  ("fish", "ru", "plain,run\t"), ("bash", "-5", "plain,")])
def test_a_well_formed_request_is_answered_as_click_answers_it(shell, cword, answer, tmp_path):
    # (a negative index is click's to read as it does: it answers, exit 0)
    done = installed(env={"_ARMCTL_COMPLETE": f"{shell}_complete", "COMP_WORDS": "armctl ru", "COMP_CWORD": cword},
                     cwd=tmp_path)
    assert (done.returncode, done.stderr) == (0, "") and answer in done.stdout, done


def test_an_instruction_click_does_not_know_stays_clicks_silent_exit_1(tmp_path):
    for instruction in ("tcsh_complete", "bash_frobnicate", "bash"):
        done = installed(env={"_ARMCTL_COMPLETE": instruction, "COMP_WORDS": "armctl ru", "COMP_CWORD": "1"},
                         cwd=tmp_path)
        assert (done.returncode, done.stdout, done.stderr) == (1, "", ""), (instruction, done)


# --- 2. a TOML syntax error is FILE:LINE:COL: message, as every other input error of armctl ---------

JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F6000\n"
BAD_PROFILE = 'name = "p"\n[connector\n'  # line 2, column 11: the ']' missing
BAD_PROFILE_LINE = "p.toml:2:11: invalid TOML: Expected ']' at the end of a table declaration"
TOML_POSITIONS = {  # text → (line, column, tomllib's message without its "(at …)")
    "an illegal character": ('port = "x\nbaud = 3\n', 1, 10, "Illegal character '\\n'"),
    "CRLF line ends": ("a = 1\r\n[x\r\n", 2, 3, "Expected ']' at the end of a table declaration"),
    "at the end of the document": ("a = 1\nb = ", 2, 5, "Invalid value"),
    "at the end, after a newline": ("x = [1,\n2,\n", 3, 1, "Invalid value"),
    "on the first line": ("a = ", 1, 5, "Invalid value"),
}


@pytest.mark.parametrize("case", TOML_POSITIONS)
def test_in_process_a_toml_error_leads_with_file_line_column(case):
    from armctl.core.toml_reading import parse_toml
    from armctl.errors import ProfileError

    text, line, column, message = TOML_POSITIONS[case]
    with pytest.raises(ProfileError) as caught:
        parse_toml(text.encode(), "x.toml")
    assert str(caught.value) == f"x.toml:{line}:{column}: invalid TOML: {message}"


def test_the_position_tomllib_gives_as_attributes_is_taken_as_given():
    # Python 3.14's TOMLDecodeError carries msg, lineno and colno (3.11–3.13: only the message's
    # words): the same line is printed from either
    import tomllib

    from armctl.core.toml_reading import parse_toml
    from armctl.errors import ProfileError

    class WithAttributes(tomllib.TOMLDecodeError):  # and a message whose words would give another place
        msg, lineno, colno = "Expected ']' at the end of a table declaration", 2, 11

    def loads(text):
        raise WithAttributes("Expected ']' at the end of a table declaration (at line 9, column 9)")

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(tomllib, "loads", loads)
        with pytest.raises(ProfileError) as caught:
            parse_toml(BAD_PROFILE.encode(), "p.toml")
    assert str(caught.value) == BAD_PROFILE_LINE


@pytest.mark.parametrize("how", ["--profile", "sim://?profile=", "armctl.toml profile =", "armctl.toml"])
def test_the_installed_command_prints_file_line_column_exit_2(how, tmp_path):
    (tmp_path / "job.txt").write_text(JOB)
    (tmp_path / "p.toml").write_text(BAD_PROFILE)
    if how == "--profile":
        done = installed("estimate", "--profile", "p.toml", "job.txt", cwd=tmp_path)
        expected = f"armctl: {BAD_PROFILE_LINE}"
    elif how == "sim://?profile=":
        done = installed("run", "--port", "sim://?clock=virtual&profile=p.toml", "--no-live", "job.txt", cwd=tmp_path)
        expected = f"armctl: --port: sim:// option profile: {BAD_PROFILE_LINE}"
    elif how == "armctl.toml profile =":
        (tmp_path / "armctl.toml").write_text('profile = "p.toml"\n')
        done = installed("config", cwd=tmp_path)
        expected = f"armctl: {tmp_path}/{BAD_PROFILE_LINE}"
    else:
        (tmp_path / "armctl.toml").write_text('port = "sim://\nbaud = 9600\n')
        done = installed("config", cwd=tmp_path)
        expected = f"armctl: {tmp_path / 'armctl.toml'}:1:15: invalid TOML: Illegal character '\\n'"
    assert (done.returncode, one_line(done.stderr)) == (2, expected), done


# --- 3. `armctl config` shows the profile's name with its control characters escaped ------------------

EVIL_NAME = "evil\x1b[2J\x1b]0;pwned\x07\x9b31m"  # clear the screen, retitle the terminal, C1 CSI
EVIL_TOML = '[profile]\nname = "evil\\u001b[2J\\u001b]0;pwned\\u0007\\u009b31m"\n'
CONTROLS = ("\x1b", "\x07", "\x9b")


def test_the_installed_config_escapes_the_profiles_name(tmp_path):
    (tmp_path / "armctl.toml").write_text(EVIL_TOML)
    done = installed("config", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    line = next(line for line in done.stdout.splitlines() if line.startswith("profile "))
    assert not any(c in done.stdout for c in CONTROLS), repr(line)
    assert r"(evil\x1b[2J\x1b]0;pwned\x07\x9b31m)" in line, repr(line)


def test_in_process_config_on_a_terminal_escapes_the_profiles_name(tmp_path, monkeypatch):
    (tmp_path / "armctl.toml").write_text(EVIL_TOML)
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    result = CliRunner().invoke(main, ["config"], color=True)  # as on a terminal: click strips no CSI
    assert result.exit_code == 0, result.output
    assert not any(c in result.stdout for c in CONTROLS), repr(result.stdout)
    assert r"evil\x1b[2J" in result.stdout


def test_config_json_keeps_the_name_as_it_is(tmp_path):
    # JSON is data, its escapes are JSON's: the name reads back exactly
    import json

    (tmp_path / "armctl.toml").write_text(EVIL_TOML)
    done = installed("config", "--json", cwd=tmp_path)
    assert done.returncode == 0 and not any(c in done.stdout for c in "\x1b\x07"), done
    assert json.loads(done.stdout)["settings"]["profile"]["value"] == f"[profile] table ({EVIL_NAME})"


# --- 4. a sim://?profile=FILE is read once: the profile checked is the profile the simulator uses --

def _profile_text(name: str) -> str:
    return f'name = "{name}"\n'


def _swap_after_first_read(monkeypatch, path: Path, then: str) -> list:
    """Every read of ``path`` counted; after the first, the file is replaced by ``then`` (an edit
    made between the port's check and its opening)."""
    import armctl.host.profile as profile_module

    reads, real = [], profile_module.read_toml

    def read_toml(target, *args, **kwargs):
        data = real(target, *args, **kwargs)
        if Path(target).resolve() == path.resolve():
            reads.append(data)
            if len(reads) == 1:
                path.write_text(then)
        return data

    monkeypatch.setattr(profile_module, "read_toml", read_toml)
    return reads


def test_in_process_the_simulator_runs_the_profile_that_was_checked(tmp_path, monkeypatch):
    from armctl.host.link import connect

    path = tmp_path / "p.toml"
    path.write_text(_profile_text("checked"))
    reads = _swap_after_first_read(monkeypatch, path, _profile_text("edited later"))
    link, _ = connect(f"sim://?clock=virtual&profile={path}", None)
    try:
        assert link.port.model.profile.name == "checked"
    finally:
        link.close()
    assert len(reads) == 1


def test_in_process_run_is_not_refused_for_a_file_spoilt_after_its_check(tmp_path, monkeypatch):
    (tmp_path / "job.txt").write_text(JOB)
    path = tmp_path / "p.toml"
    path.write_text(_profile_text("checked"))
    reads = _swap_after_first_read(monkeypatch, path, BAD_PROFILE)
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    result = CliRunner().invoke(main, ["run", "--port", "sim://?clock=virtual&profile=p.toml", "--no-live", "job.txt"])
    assert result.exit_code == 0, result.output
    assert len(reads) == 1


@pytest.mark.parametrize("serve", ["--pty", "--tcp"])
def test_in_process_a_served_simulator_runs_the_profile_that_was_checked(serve, tmp_path, monkeypatch):
    import armctl.sim.bridge as bridge

    path = tmp_path / "p.toml"
    path.write_text(_profile_text("checked"))
    reads = _swap_after_first_read(monkeypatch, path, _profile_text("edited later"))
    served = []

    def serve_pty(options, ready, keep_serving, model, on_arm):
        served.append(model.profile.name)

    def serve_tcp(port, options, ready, keep_serving):
        served.append(bridge.SimulatedArm(options).profile.name)

    monkeypatch.setattr(bridge, "serve_pty", serve_pty)
    monkeypatch.setattr(bridge, "serve_tcp", serve_tcp)
    arguments = ["--pty"] if serve == "--pty" else ["--tcp", "50007"]
    result = CliRunner().invoke(main, ["sim", *arguments, "--url", f"sim://?profile={path}"])
    assert result.exit_code == 0, result.output
    assert served == ["checked"] and len(reads) == 1


SWAP_HOOK = '''
import atexit, os, sys
target, then, tally = os.environ["REVIEW7_PROFILE"], os.environ["REVIEW7_THEN"], os.environ["REVIEW7_TALLY"]
opens, busy = [], []
def hook(event, args):
    if event == "open" and not busy and isinstance(args[0], str) and os.path.abspath(args[0]) == target:
        opens.append(1)
        if len(opens) == 2:  # a second read: the file was edited after the first
            busy.append(1)
            with open(target, "w") as file:
                file.write(then)
atexit.register(lambda: open(tally, "w").write(str(len(opens))))
sys.addaudithook(hook)
'''


def test_the_installed_command_opens_the_profile_once(tmp_path):
    # an audit hook in the child (sitecustomize) counts the opens of the file and spoils it before
    # a second one: read once, the job runs on the profile checked
    (tmp_path / "job.txt").write_text(JOB)
    (tmp_path / "p.toml").write_text(_profile_text("checked"))
    (tmp_path / "hook").mkdir()
    (tmp_path / "hook" / "sitecustomize.py").write_text(SWAP_HOOK)
    env = {"PYTHONPATH": str(tmp_path / "hook"), "REVIEW7_PROFILE": str(tmp_path / "p.toml"),
           "REVIEW7_THEN": BAD_PROFILE, "REVIEW7_TALLY": str(tmp_path / "tally")}
    done = installed("run", "--port", "sim://?clock=virtual&profile=p.toml", "--no-live", "-q", "job.txt",
                     env=env, cwd=tmp_path)
    assert (tmp_path / "tally").read_text() == "1", done.stderr
    assert done.returncode == 0, done.stderr
