"""Issue 26 item 5 and issue 22's decode: ``decode`` of a run log gives each frame its time and
direction, and ``decode`` streams — its memory does not grow with its input.

The streaming scanner finds exactly ``scan_frames``' chunks however the input is cut (a
Hypothesis property); peak memory is measured with tracemalloc on generated inputs 4x apart,
with the block sizes made small so that small inputs already lie far beyond them (the memory
bound is the block and probe sizes, whatever they are; benchmarks/decode_memory.py measures
the installed command at full size).
"""

from __future__ import annotations

import io
import json
import subprocess
import sys
import tracemalloc
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.ui import decode
from armctl.ui.decode import FrameScanner, decode_stream
from armctl.ui.formats import decoded_record, describe_decoded
from armctl.core.protocol import scan_frames

ARMCTL = Path(sys.executable).with_name("armctl")
STATUS = bytes.fromhex("ce083400000bb800cf")
COMMAND = bytes.fromhex("ee36000000484300000000000000000000000000000000000000000000000000000000000000000000000000000000ef")
PIECES = [STATUS, COMMAND, b"\xce", b"\xee", b"\xcf", b"\xef", b"\xfc", b"junk", COMMAND[:30], STATUS[:5]]


@settings(max_examples=300, deadline=None)
@given(parts=st.lists(st.sampled_from(PIECES), max_size=40), cuts=st.lists(st.integers(0, 2000), max_size=12))
def test_the_streaming_scanner_finds_what_scan_frames_finds(parts, cuts):
    data = b"".join(parts)
    scanner, chunks, start = FrameScanner(), [], 0
    for cut in sorted(set(cuts)) + [len(data)]:
        cut = min(cut, len(data))
        chunks += scanner.feed(data[start:cut])
        start = max(start, cut)
    chunks += scanner.finish()
    assert chunks == list(scan_frames(data))


def _log(records: int) -> bytes:
    lines = []
    for index in range(records):
        t = round(index * 0.03, 2)
        if index % 5 == 0:
            lines.append({"t": t, "dir": "tx", "hex": COMMAND.hex(), "line": index})
        lines.append({"t": t, "dir": "rx", "hex": STATUS.hex(), "kind": 0})
        if index % 7 == 0:
            lines.append({"t": t, "dir": "progress", "sent_line": index})
    return "".join(json.dumps(line) + "\n" for line in lines).encode()


def test_log_frames_carry_time_and_direction_in_log_order():
    items = list(decode_stream(io.BytesIO(_log(12)), "job.log"))
    assert [(item.t_s, item.direction) for item in items][:4] == [(0.0, "tx"), (0.0, "rx"), (0.03, "rx"), (0.06, "rx")]
    assert [item.chunk.offset for item in items if item.direction == "rx"][:3] == [0, 9, 18]  # per direction
    text = describe_decoded(items[0])
    assert text.startswith("    0.000 s  host→arm       0  motion   delay")
    record = decoded_record(items[1])
    assert (record["t"], record["direction"], record["family"]) == (0.0, "arm->host", "status")


def _peak_bytes(data: bytes) -> int:
    stream = io.BytesIO(data)  # the input itself, before measuring
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        for item in decode_stream(stream, "input"):
            describe_decoded(item)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def _peaks(kind: str) -> tuple[int, int, int, int]:
    """(peak small, peak large, size small, size large) of decoding ``kind`` input 4x apart, the
    block sizes made small."""
    decode.PROBE_BYTES = decode.BLOCK_BYTES = decode.JUNK_PIECE_BYTES = 4096

    def make(size: int) -> bytes:
        if kind == "log":
            return _log(size // 100)
        raw = (COMMAND + STATUS * 4 + b"junk") * (size // 89)
        return raw.hex().encode() if kind == "hex" else raw

    small, large = make(100_000), make(400_000)
    _peak_bytes(make(9_000))  # first use imports what describing needs: not the input's memory
    return _peak_bytes(small), _peak_bytes(large), len(small), len(large)


@pytest.mark.timeout(120)
@pytest.mark.parametrize("kind", ["raw", "hex", "log"])
def test_memory_is_flat_in_the_inputs_size(kind):
    # measured in a fresh interpreter: tracemalloc counts every thread's allocations, threads
    # other tests leave in a worker may allocate meanwhile, and under load (Python 3.13, -n 4)
    # the hex input once read 81 kB more at 4x, which it never did alone
    done = subprocess.run([sys.executable, "-c", f"import test_newcomer_decode as t; print(*t._peaks({kind!r}))"],
                          cwd=Path(__file__).parent, capture_output=True, text=True, timeout=100)
    assert done.returncode == 0, done.stderr
    peak_small, peak_large, small, large = map(int, done.stdout.split())
    # flat: the 4x input adds less than a quarter of the small input's size (a few blocks are
    # ~100 kB of constant overhead: the decoded frames' classes, formatting), and stays below half of it
    assert peak_large - peak_small < small // 4, (peak_small, peak_large, small, large)
    assert peak_large < large // 2, (peak_large, large)


@pytest.mark.timeout(60)
def test_the_installed_command_prints_time_and_direction(tmp_path):
    log = tmp_path / "job.log"
    log.write_bytes(_log(6))
    done = subprocess.run([str(ARMCTL), "decode", str(log)], capture_output=True, text=True, timeout=50)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("    0.000 s  host→arm") and lines[1].startswith("    0.000 s  arm→host")
    assert lines[2].startswith("    0.030 s  arm→host")
    done = subprocess.run([str(ARMCTL), "decode", "--json", str(log)], capture_output=True, text=True, timeout=50)
    records = [json.loads(line) for line in done.stdout.splitlines()]
    assert [(r["t"], r["direction"]) for r in records][:3] == [(0.0, "host->arm"), (0.0, "arm->host"), (0.03, "arm->host")]


@pytest.mark.timeout(60)
def test_hex_that_stops_being_hex_beyond_the_probe_is_exit_2(tmp_path):
    path = tmp_path / "odd.hex"
    path.write_bytes(COMMAND.hex().encode() * 2000 + b"\nzz\n")
    done = subprocess.run([str(ARMCTL), "decode", str(path)], capture_output=True, text=True, timeout=50)
    assert done.returncode == 2 and "not hex text" in done.stderr and "Traceback" not in done.stderr
