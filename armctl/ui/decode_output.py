"""``armctl decode``'s output: each ``Decoded`` of the input (armctl/ui/decode.py) printed as a
line (or a JSON line), a write per 1,024 lines; the tally, a log's job records (script, first
line, port) and the line that ended its intact prefix on stderr; the exit code (1 when that
line is damaged: it and the lines after it were not shown; 0 for the torn last line a crash
leaves).  The input is a regular file or stdin
(``open_input``)."""

from __future__ import annotations

import json
import sys
from contextlib import contextmanager

import click

from ..errors import EXIT_PROBLEMS, UsageFailure


def print_decoded(source: str, as_json: bool) -> int:
    """Decode ``source`` (a path, ``-``: stdin) to stdout; the exit code."""
    from .decode import NotHex, decode_stream
    from .formats import ChunkTally, decoded_record, describe_decoded

    tally = ChunkTally()
    out = sys.stdout
    damaged: list = []  # the LogDamage that ended a log's intact prefix, if one did
    jobs: list = []  # (line, record) of each job record of a log: its script and port
    name = "<stdin>" if source == "-" else source
    with open_input(source) as stream:
        lines: list[str] = []
        try:
            for item in decode_stream(stream, name, damaged=damaged, jobs=jobs):
                tally.add(item.chunk)
                lines.append(json.dumps(decoded_record(item)) if as_json else describe_decoded(item))
                if len(lines) >= 1024:  # a write per line costs more than the decoding
                    out.write("\n".join(lines) + "\n")
                    lines = []
        except NotHex as error:
            raise UsageFailure(f"{source}:{error.where}: {error}" if error.where else f"{source}: {error}") from None
        finally:
            if lines:
                out.write("\n".join(lines) + "\n")
    for number, job in jobs:
        click.echo(f"{name}:{number}: {describe_job(job)}", err=True)
    for damage in damaged:
        click.echo(f"{name}:{damage.number}: " + (
            "the last line is torn (the crash's cut): ignored" if damage.torn else
            f"a damaged record ({damage.why}): the log is decoded up to it; it and the {damage.after} line(s) "
            "after it are not shown (only a log's intact prefix is trusted)"), err=True)
    click.echo(tally.line(), err=True)
    return EXIT_PROBLEMS if any(not damage.torn for damage in damaged) else 0


def describe_job(job: dict) -> str:
    """A log's job record for people: ``job JOB.txt from line 1 on port /dev/ttyUSB0 (usb 0403:6001
    serial A1)`` — the port and the identity of the arm on it."""
    port, arm = job.get("port"), job.get("arm")
    where = (f"on port {plain_text(port)} ({plain_text(arm) if isinstance(arm, str) else 'arm unknown'})"
             if isinstance(port, str) else "port unknown (a log written before armctl recorded it)")
    return f"job {plain_text(job.get('script'))} from line {plain_text(job.get('from_line'))} {where}"


def plain_text(value) -> str:
    """``value`` as text with its control characters escaped (``\\x1b``): a log's names are the
    log's, and a log from elsewhere must not drive the terminal (retitle, clear, recolour it)."""
    text = str(value)
    return text if text.isprintable() else "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


@contextmanager
def open_input(path: str):
    """``path`` opened for binary reading (``-``: stdin, left open); unreadable: exit 2.  Only a
    regular file (``inputs.open_regular``): a named pipe, device or directory is refused before
    it is opened (``UnusableInput``: exit 2) — stdin is the way to give a stream."""
    from ..host.inputs import open_regular

    if path == "-":
        yield sys.stdin.buffer
        return
    try:
        stream = open_regular(path)
    except OSError as error:
        raise UsageFailure(f"cannot read {path}: {error.strerror or error}") from None
    with stream:
        yield stream
