"""Property: whatever a crash, corruption or an edit leaves of a real journal, ``--resume`` is
refused with nothing sent, or it sends every line not yet executed exactly once and no line
the arm already ran — judged by the simulator's own record of executed frames.

Strategy: real journals are made once per (script, crash point) — the job through the API on a
virtual-clock simulator, stopped after ``n`` frames with ``abort="none"`` (tests/journal_crash.py)
— and each example only mutates their bytes:

- a crash's cut: the log from its durable end (the record of the last frame written, fsynced
  before the frame went out) to anywhere after it, mid-record included: what a power cut leaves;
- damage: bytes flipped, replaced, deleted or inserted anywhere, lines dropped, repeated or
  swapped, a number in a record changed (an edit by hand, its checksum left as it was).  Line
  breaks stay where they are, and the log's last complete line is never dropped or moved: damage
  that deletes the line break ending the log's last durable frame record makes it a torn last
  line, and a last record dropped (or moved away and dropped) is a cut before the durable end —
  neither is what a crash leaves, and no check of records can tell them from what it does
  (nothing after them says they were there).  Both were found by this property before the rule.

Then the resume's decision (``read_resume_lines``, ``ResumePoint.line_for`` with the arm's report
at rest) is judged against the simulator's record: refused, or the line whose compilation is
exactly the frames the arm has not run.  Each distinct decision of each crash is also carried
out once end to end (``Arm.run(resume=)`` on a simulator brought to the same crash), and the
arm's own record must then hold every frame of the job exactly once — or, refused, nothing more
received.

Scripts: scripts/joint_routine.txt (returns to home again and again), pick_and_place.txt,
draw_square_circle.txt (arcs), worktable_origin.txt (G54), sd_program.txt (POSE, PROGRAM) and
one written here that comes back to the same point with delays, PWM-only and G91 moves between.
Repeat blocks are left out: a resume inside one starts the block again, as ``--from-line`` does.

``ARMCTL_JOURNAL_EXAMPLES`` sets the number of examples (default 2,000; 20,000 by hand).
"""

from __future__ import annotations

import functools
import io
import os
import random
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from armctl import Arm
from armctl.errors import ResumeRefused
from armctl.core.joblog import JournalDamaged, NotProven, read_resume_lines
from armctl.script.files import read_script

from journal_crash import VIRTUAL, Crash, crash_into, make_crash, ran, sent

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = int(os.environ.get("ARMCTL_JOURNAL_EXAMPLES", "2000"))

REVISIT = """\
G1 X220 Y0 Z200 A180 B0 C0 S1000 F6000
G1 X260
G4 P200
G1 X220
G1 S2000
G1 X260
G91
G1 X-40
G90
G1 X260 S1000
G4 P100
G1 X220 Y0
"""


@pytest.fixture(scope="module")
def crashes(tmp_path_factory):
    folder = tmp_path_factory.mktemp("journals")
    revisit = folder / "revisit.txt"
    revisit.write_text(REVISIT)
    scripts = [ROOT / "scripts" / f"{name}.txt" for name in
               ("joint_routine", "pick_and_place", "draw_square_circle", "worktable_origin", "sd_program")] + [revisit]
    made: dict = {}

    def crash(index: int, point: float) -> Crash:
        script = scripts[index % len(scripts)]
        total = _frame_count(script)
        n = 1 + min(total - 1, int(point * total))
        if (script, n) not in made:
            made[(script, n)] = make_crash(script, n, folder / f"{script.stem}-{n}.log")
        return made[(script, n)]

    crash.folder = folder
    return crash


@functools.cache
def _snapshot(script: Path):
    """The script as read once (the scripts do not change during the run; each example reads its
    journal, not the script, as its own input)."""
    return read_script(str(script))


@functools.cache
def _frame_count(script: Path) -> int:
    return len(list(_snapshot(script).compile()))


_NUMBER = re.compile(rb"-?\d+(?:\.\d+)?")


@st.composite
def mutations(draw):
    """A crash's cut (a fraction of the tail after the durable end) and up to 4 kinds of damage."""
    cut = draw(st.floats(0, 1))
    damage = draw(st.lists(st.tuples(st.sampled_from(["flip", "byte", "delete", "insert", "number", "drop", "repeat",
                                                      "swap"]),
                                     st.floats(0, 1, exclude_max=True), st.integers(0, 255)), max_size=4))
    if draw(st.booleans()):
        damage = []  # a clean crash: only the cut
    return cut, damage


def mutate(crash: Crash, cut: float, damage) -> bytes:
    data = crash.log[: crash.durable_end + int(cut * (len(crash.log) - crash.durable_end))]
    for kind, where, value in damage:
        if not data:
            break
        at = int(where * len(data))
        if kind in ("drop", "repeat", "swap"):
            lines = data.split(b"\n")  # the last is the torn piece after the last line break ("" if none)
            last = len(lines) - 2  # the last complete line: never dropped or moved (see the docstring)
            k = int(where * (len(lines) - 1))
            if kind == "repeat":
                lines.insert(k, lines[k])
            elif kind == "drop" and k < last:
                del lines[k]
            elif kind == "swap" and k + 1 < last:
                lines[k], lines[k + 1] = lines[k + 1], lines[k]
            data = b"\n".join(lines)
            continue
        if kind == "number":
            numbers = list(_NUMBER.finditer(data))
            if numbers:
                match = numbers[int(where * len(numbers))]
                data = data[: match.start()] + str(int(float(match.group())) + 1 + value % 7).encode() + data[match.end():]
            continue
        if data[at:at + 1] == b"\n":
            continue  # line breaks stay (see the module's docstring)
        if kind == "flip":
            byte = data[at] ^ (1 << (value % 8))
            if byte != 0x0A:
                data = data[:at] + bytes([byte]) + data[at + 1:]
        elif kind == "byte" and value != 0x0A:
            data = data[:at] + bytes([value]) + data[at + 1:]
        elif kind == "delete":
            data = data[:at] + data[at + 1:]
        elif kind == "insert":
            data = data[:at] + bytes([value]) + data[at:]
    return data


def decide(crash: Crash, data: bytes):
    """The resume's decision: ("refused", why) or ("line", L or None)."""
    snapshot = _snapshot(crash.script)
    try:
        point = read_resume_lines(io.StringIO(data.decode("utf-8", errors="replace")), snapshot.name, snapshot.data)
        return "line", point.line_for(*crash.rest)
    except (ResumeRefused, JournalDamaged, NotProven) as error:
        return "refused", type(error).__name__


_carried_out: dict = {}
_decided: dict = {}  # (script, crash point, the mutated log's bytes) -> decide()'s answer


def carry_out(crash: Crash, data: bytes, decision, folder: Path) -> None:
    """The decision end to end, once per (crash, decision): a simulator brought to the same crash,
    then ``Arm.run(resume=)``; judged by the arm's own record."""
    key = (crash.script, crash.n, decision)
    if key in _carried_out:
        return
    _carried_out[key] = True
    event("carried out end to end on a simulator (first time for this crash and decision)")
    log, mutated = folder / "crash.log", folder / "mutated.log"
    mutated.write_bytes(data)
    with Arm.open(port=VIRTUAL) as arm:
        crash_into(arm, crash.script, crash.n, log)
        before = sent(arm)
        if decision[0] == "refused":
            with pytest.raises((ResumeRefused, JournalDamaged, NotProven)):
                arm.run(crash.script, resume=mutated)
            assert sent(arm) == before, "a refused resume sent frames"
            return
        result = arm.run(crash.script, resume=mutated)
        assert result.outcome == "finished", result
        assert ran(arm) == crash.full, f"resumed at {decision[1]}: the arm's record is not every line once"


@settings(max_examples=EXAMPLES, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture, HealthCheck.data_too_large])
@given(script=st.integers(0, 5), point=st.floats(0, 1), change=mutations())
@pytest.mark.timeout(1800)
def test_a_resume_is_refused_or_runs_every_line_exactly_once(crashes, script, point, change):
    crash = crashes(script, point)
    data = mutate(crash, *change)
    key = (crash.script, crash.n, data)
    if key not in _decided:  # a pure function of the bytes: 2,000 examples hold about 1,200 distinct logs
        _decided[key] = decide(crash, data)
    decision = _decided[key]
    event(f"{decision[0]}{'' if decision[0] == 'line' else ': ' + decision[1]}")
    if decision[0] == "line":
        assert crash.correct(decision[1]), (
            f"{crash.script.name} crashed after {crash.n} frames: the resume at line {decision[1]} runs a line twice "
            f"or skips one")
    carry_out(crash, data, decision, crashes.folder)


def test_the_mutations_reach_every_outcome(crashes):
    """The property is not vacuous: clean cuts resume, damage is refused, both occur."""
    rng = random.Random(7)
    outcomes = set()
    for index in range(6):
        crash = crashes(index, 0.5)
        outcomes.add(decide(crash, mutate(crash, rng.random(), []))[0])
        outcomes.add(decide(crash, mutate(crash, 0.5, [("flip", 0.3, 5)]))[0])
    assert outcomes == {"line", "refused"}
