"""One JSON convention: ``--json`` on every command that prints data, the data alone on stdout
(one document, or JSON lines for a stream), every message on stderr.

Each command runs in-process (CliRunner, whose result keeps stdout and stderr apart) in an
empty working directory with ``ARMCTL_PORT`` cleared, and the whole set once more through the
installed command in a fresh process.  A script with a warning (L103 against the illustrative
workspace) makes sure a message exists that must stay off stdout.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.host.profile import find_config

SIM = "sim://?clock=virtual"
WARNING_SCRIPT = "G1 X450 Y0 Z150 A180 B-90 C0 S1500 F3000\n"  # L103: outside the illustrative workspace (the arm still reaches it)


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMCTL_PORT", raising=False)
    assert find_config(tmp_path)[0] is None, "an armctl.toml above the temporary directory"
    (tmp_path / "job.txt").write_text(WARNING_SCRIPT, encoding="utf-8")


# (arguments, a text stderr must hold, a check of the parsed stdout)
COMMANDS = {
    "ports": (["ports", "--json"], None, lambda data: isinstance(data, list)
              and all(set(p) == {"device", "description", "hwid"} for p in data)),
    "estimate": (["estimate", "job.txt", "--json"], "L103", lambda data: data["frames"] == 1),
    "status": (["status", "--once", "--json", "--port", SIM], "using the built-in simulator",
               lambda data: data["x"] == 210.0),
    "lint": (["lint", "job.txt", "--json"], "Found 1 warning", lambda data: [f["code"] for f in data] == ["L103"]),
    "lint --format json": (["lint", "job.txt", "--format", "json"], "Found 1 warning",
                           lambda data: [f["code"] for f in data] == ["L103"]),
    "config": (["config", "--json"], None, lambda data: data["settings"]["port"]["source"] == "default"),
    "probe": (["probe", "--no-motion", "--json", "--port", SIM], "using the built-in simulator",
              lambda data: data["fifo_frames"] == 200),
}


@pytest.mark.parametrize("name", list(COMMANDS))
def test_json_on_stdout_messages_on_stderr(name):
    args, message, check = COMMANDS[name]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    assert check(json.loads(result.stdout)), result.stdout
    if message is not None:
        assert message in result.stderr and message not in result.stdout


def test_lint_json_and_format_json_print_the_same_document():
    assert CliRunner().invoke(main, ["lint", "job.txt", "--json"]).stdout == \
        CliRunner().invoke(main, ["lint", "job.txt", "--format", "json"]).stdout


def test_lint_json_with_another_format_is_a_usage_error():
    result = CliRunner().invoke(main, ["lint", "job.txt", "--json", "--format", "github"])
    assert result.exit_code == 2 and "--json is --format json" in result.stderr and result.stdout == ""


def test_ports_json_with_no_port_is_an_empty_list(monkeypatch):
    from serial.tools import list_ports

    monkeypatch.setattr(list_ports, "comports", lambda: [])
    result = CliRunner().invoke(main, ["ports", "--json"])
    assert result.exit_code == 0 and json.loads(result.stdout) == []
    assert "no serial ports found" in result.stderr


def test_installed_command_keeps_stdout_json(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "ARMCTL_PORT"}
    for name, (args, message, check) in COMMANDS.items():
        done = subprocess.run([sys.executable, "-m", "armctl", *args], capture_output=True, text=True,
                              timeout=60, env=env, cwd=tmp_path)
        assert done.returncode == 0, (name, done.stderr)
        assert check(json.loads(done.stdout)), (name, done.stdout)
        if message is not None:
            assert message in done.stderr, (name, done.stderr)


# --- the commands that print a stream of records: JSON lines ------------------------------------

def _strict_json_lines(text: str) -> list:
    """Every line one JSON value, with no NaN/Infinity (which JSON does not have)."""
    def refuse(constant):
        raise ValueError(f"{constant} is not JSON")
    return [json.loads(line, parse_constant=refuse) for line in text.splitlines()]


def test_compile_json_is_format_json_and_refuses_another_format():
    lines = _strict_json_lines(CliRunner().invoke(main, ["compile", "job.txt", "--json"]).stdout)
    assert lines == _strict_json_lines(CliRunner().invoke(main, ["compile", "job.txt", "--format", "json"]).stdout)
    assert [record["command"] for record in lines] == ["LinearMove"]
    result = CliRunner().invoke(main, ["compile", "job.txt", "--json", "--format", "hex"])
    assert result.exit_code == 2 and "--json is --format json" in result.output


def test_run_json_is_json_lines_ending_in_one_summary():
    result = CliRunner().invoke(main, ["run", "job.txt", "--json", "--port", SIM])
    assert result.exit_code == 0, result.output
    events = _strict_json_lines(result.stdout)
    assert events[0]["event"] == "started" and [e["event"] for e in events].count("summary") == 1
    assert events[-1]["event"] == "summary" and events[-1]["outcome"] == "finished"
    assert "L103" in result.stderr and "L103" not in result.stdout
    dry = CliRunner().invoke(main, ["run", "job.txt", "--json", "--dry-run"])
    assert dry.exit_code == 2 and dry.stdout == "" and "armctl compile --json" in dry.stderr


def test_decode_json_names_every_chunk_and_keeps_the_summary_on_stderr(tmp_path):
    frames = CliRunner().invoke(main, ["compile", "job.txt"]).stdout
    (tmp_path / "frames.hex").write_text(frames + "ce0000807f000064cf\n" + "01 02\n", encoding="utf-8")
    result = CliRunner().invoke(main, ["decode", "frames.hex", "--json"])
    assert result.exit_code == 0, result.output
    records = _strict_json_lines(result.stdout)
    assert [r["family"] for r in records] == ["motion", "invalid", "junk"]
    assert records[0]["fields"]["x_mm"] == 450 and records[1]["error"].endswith("not a finite number")
    assert "1 command frame(s)" in result.stderr


@settings(max_examples=200, deadline=None)
@given(data=st.binary(max_size=200))
def test_decode_json_of_any_bytes_is_strict_json_lines(data):
    from armctl.ui.formats import bytes_from_input, chunk_record
    from armctl.core.protocol import scan_frames

    text = "\n".join(json.dumps(chunk_record(chunk)) for chunk in scan_frames(bytes_from_input(data)))
    records = _strict_json_lines(text)
    # the records' bytes spell the input back, in order
    assert b"".join(bytes.fromhex(r["hex"]) for r in records) == bytes_from_input(data)
