"""``armctl decode``: every frame named (family, command, fields with units), from hex text,
raw bytes, a mix with status frames and junk, and the JSON-lines log of ``armctl run --log``.

Inputs are built with ``struct`` straight from PROTOCOL.md (the encoder of test_cli_compile.py
and, for status frames, ``0xCE d0..d5 kind 0xCF`` with big-endian signed 16-bit words, H8).
"""

from __future__ import annotations

import json
import re
import struct
from pathlib import Path

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main

from test_cli_compile import EVERY, EXPECTED, control, motion

SCRIPTS = Path(__file__).resolve().parent / "data" / "scripts_cli"

# What decode must say for each frame of every_statement.txt: family, command, and some fields
# with their units (in the order decode prints them).
NAMED = [
    ("motion", "linear move", "x=250 mm y=-120 mm z=150 mm b0=180 deg b1=0 deg w=0 deg pwm=1000 µs speed=3000 mm/min"),
    ("motion", "linear move", "pwm=1500 µs", "pwm_channel=2"),
    ("motion", "linear move", "e0=5 deg e1=-5 deg"),
    ("motion", "linear move", "x=262.5 mm y=-102.5 mm z=145 mm"),
    ("motion", "arc start", "radius=30 mm speed=900 mm/min"),
    ("motion", "arc end", "x=220 mm y=0 mm z=140 mm", "speed=600 mm/min"),
    ("motion", "accelerated linear move", "mode=0", "accel=-800 mm/s² speed1=2400 mm/min speed0=0 mm/min"),
    ("motion", "accelerated linear move", "mode=1", "accel=1600 mm/s²"),
    ("motion", "accelerated linear move", "mode=2", "speed1=3600 mm/min speed0=600 mm/min"),
    ("motion", "joint move", "j1=10 deg j2=20 deg j3=30 deg j4=0 deg j5=90 deg j6=-45 deg pwm=1200 µs speed=45 deg/s",
     "smoothing=3"),
    ("motion", "delay", "delay=250 ms"),
    ("motion", "M code", "number=3"),
    ("control", "set worktable origin", "x=10 mm y=20 mm z=-5 mm"),
    ("control", "reset arm"),
    ("control", "reset connector"),
    ("control", "pause toggle"),
    ("control", "pause toggle"),
    ("control", "go to fixed pose", "pose=2"),
    ("control", "run SD program", "program=7"),
    ("control", "structure mode", "mode=0"),
    ("control", "structure mode", "mode=1"),
    ("motion", "delay", "delay=120 ms"),
    ("motion", "delay", "delay=120 ms"),
    ("motion", "M code", "number=30"),
]
LOGGED = re.compile(r"^ *(?P<t>\d+\.\d{3}) s  (?P<direction>host→arm|arm→host)  (?P<rest>.*)$")
DECODED = re.compile(r"^ *(?P<offset>\d+)  (?P<family>motion |control|status |invalid|\?\? ) +(?P<rest>.*)$")


def status(kind: int, d: bytes) -> bytes:
    assert len(d) == 6
    return bytes([0xCE]) + d + bytes([kind, 0xCF])


def words(*values: int) -> bytes:
    return struct.pack(">3h", *values)


def decode(*args, input=None):
    return CliRunner().invoke(main, ["decode", *map(str, args)], input=input)


def parsed(stdout: str) -> list[dict]:
    lines = stdout.splitlines()
    matches = [DECODED.match(line) for line in lines]
    assert all(matches), [line for line, m in zip(lines, matches) if not m]
    return [m.groupdict() for m in matches]


def assert_names_every_frame(stdout: str, start_offset: int = 0) -> None:
    rows = parsed(stdout)
    assert len(rows) == len(NAMED)
    for index, (row, (family, name, *fields)) in enumerate(zip(rows, NAMED)):
        assert int(row["offset"]) == start_offset + 48 * index
        assert row["family"].strip() == family
        assert row["rest"].startswith(name + " ") or row["rest"] == name, row
        for field in fields:
            assert field in row["rest"], (index, field, row["rest"])


@pytest.fixture(autouse=True)
def _empty_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def test_decode_of_the_compile_output_names_every_frame(tmp_path):
    hex_file = tmp_path / "every.hex"
    compiled = CliRunner().invoke(main, ["compile", str(EVERY), "-o", str(hex_file)])
    assert compiled.exit_code == 0, compiled.output
    result = decode(hex_file)
    assert result.exit_code == 0, result.output
    assert_names_every_frame(result.stdout)
    assert result.stderr.strip() == "24 command frame(s), 0 status frame(s), 0 invalid frame(s), 0 byte(s) in no frame"


def test_decode_reads_raw_bytes(tmp_path):
    raw = tmp_path / "every.bin"
    raw.write_bytes(b"".join(frame for _, frame in EXPECTED))
    result = decode(raw)
    assert result.exit_code == 0
    assert_names_every_frame(result.stdout)


def test_hex_whitespace_and_case_do_not_matter(tmp_path):
    text = "\r\n".join(" ".join(frame.hex().upper()[i : i + 8] for i in range(0, 96, 8)) for _, frame in EXPECTED)
    (tmp_path / "spaced.hex").write_text("\n\t" + text + "\r\n\n")
    result = decode(tmp_path / "spaced.hex")
    assert_names_every_frame(result.stdout)


def test_dash_and_no_argument_read_stdin():
    text = "".join(frame.hex() + "\n" for _, frame in EXPECTED)
    assert_names_every_frame(decode("-", input=text).stdout)
    assert_names_every_frame(decode(input=text).stdout)


def test_a_mix_of_command_and_status_frames_with_junk_marks_the_junk(tmp_path):
    g1 = motion("1", 1, f1=250, f2=-120, f3=150, f4=180, f7=1000, f11=3000)
    pause = control(30, 3, b"\x02")
    position = status(0, words(100, -200, 3000))  # ÷10 → mm
    joints = status(1, words(4500, -9000, 1))  # ÷100 → deg
    pwm = status(4, bytes([0, 1, 0, 0]) + struct.pack(">h", 1500))
    length = status(100, struct.pack("<f", 1234.5) + b"\0\0")  # H8: floats little-endian
    data = b"\x01\x02junk" + g1 + position + b"\xce\xcf" + joints + pause + pwm + length + g1[:47]
    (tmp_path / "mix.bin").write_bytes(data)
    result = decode(tmp_path / "mix.bin")
    assert result.exit_code == 0
    rows = [(int(r["offset"]), r["family"].strip(), r["rest"]) for r in parsed(result.stdout)]
    assert rows == [
        (0, "??", "6 byte(s) in no frame: 01 02 6a 75 6e 6b"),
        (6, "motion", rows[1][2]),
        (54, "status", "position x=10 mm y=-20 mm z=300 mm"),
        (63, "??", "2 byte(s) in no frame: ce cf"),
        (65, "status", "joints 1-3 j1=45 deg j2=-90 deg j3=0.01 deg"),
        (74, "control", "pause toggle"),
        (122, "status", "pause and PWM pause_state=1 pwm=1500 µs"),
        (131, "status", "SD file length value=1234.5"),
        (140, "??", rows[-1][2]),
    ]
    assert rows[1][2].startswith("linear move x=250 mm y=-120 mm z=150 mm")
    assert rows[-1][2].startswith("47 byte(s) in no frame: ee 31 01")  # a frame cut short is junk
    assert result.stderr.strip() == "2 command frame(s), 4 status frame(s), 0 invalid frame(s), 55 byte(s) in no frame"


def test_a_well_framed_command_with_a_field_out_of_range_is_marked_invalid(tmp_path):
    bad = motion("1", 1, f1=250, f2=0, f3=150, f4=180, f7=9000, f11=3000)  # PWM 9000 µs
    result = decode(input=bad.hex())
    rows = parsed(result.stdout)
    assert [r["family"].strip() for r in rows] == ["invalid"]
    assert "pwm_us" in rows[0]["rest"] and "9000" in rows[0]["rest"]


def test_junk_only_is_all_marked():
    result = decode(input=b"hello, arm")
    assert result.exit_code == 0
    assert [r["rest"] for r in parsed(result.stdout)] == ["10 byte(s) in no frame: 68 65 6c 6c 6f 2c 20 61 72 6d"]


def test_a_missing_file_is_a_usage_error(tmp_path):
    result = decode(tmp_path / "nope.hex")
    assert result.exit_code == 2
    assert "cannot read" in result.stderr


# --- the log of armctl run -----------------------------------------------------------------------


def test_the_run_log_is_decoded_too(tmp_path):
    log = tmp_path / "job.log"
    job = SCRIPTS / "short_job.txt"
    ran = CliRunner().invoke(main, ["run", str(job), "--port", "sim://?clock=virtual", "--no-live", "--log", str(log)])
    assert ran.exit_code == 0, ran.output
    records = [json.loads(line) for line in log.read_text().splitlines()]
    assert {r["dir"] for r in records if "hex" not in r} == {"job", "progress"}  # no bytes: decode skips them
    records = [r for r in records if "hex" in r]
    sent = [r for r in records if r["dir"] == "tx"]
    read = [r for r in records if r["dir"] == "rx"]
    assert sent and read
    compiled = CliRunner().invoke(main, ["compile", str(job)]).stdout.split()
    assert [r["hex"] for r in sent] == compiled

    result = decode(log)
    assert result.exit_code == 0
    # each frame with the time and direction of its record, in the log's order (issue 26)
    logged = [LOGGED.match(line) for line in result.stdout.splitlines()]
    assert all(logged), result.stdout
    assert [(float(m["t"]), m["direction"]) for m in logged] == \
        [(round(r["t"], 3), "host→arm" if r["dir"] == "tx" else "arm→host") for r in records]
    rows = parsed("\n".join(m["rest"] for m in logged))
    assert [r["family"].strip() for r in rows] == ["motion" if r["dir"] == "tx" else "status" for r in records]
    assert all(row["rest"].startswith("linear move") or row["rest"].startswith("delay")
               for row in rows if row["family"].strip() == "motion")
    assert f"{len(sent)} command frame(s), {len(read)} status frame(s), 0 invalid frame(s), 0 byte(s) in no frame" \
        in result.stderr
