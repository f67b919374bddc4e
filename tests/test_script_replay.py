"""A repeat pass that ran exactly as the one before is run again from its statements (issue 23,
armctl/script/repeats.py ``_Pass``): the compilation must be the one that executes every pass —
the same statements (every field, every bit, the pass numbers), diagnostics, lines run and
modal state — and the replay must happen (the lines executed are counted)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from armctl.script import compile_text, compiler, repeats
from armctl.script.execute import StatementExecution

ROOT = Path(__file__).resolve().parents[1]
START = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\n"

TEXTS = {
    "absolute": START + "O1 repeat [50]\nG1 Y-1\nG1 Y0\nO1 endrepeat\nG1 Z160\n",
    "nested": START + "O1 repeat [6]\nO2 repeat [5]\nG1 Y-1\nG1 Y0\nO2 endrepeat\nG1 Z151\nG1 Z150\nO1 endrepeat\n",
    "relative": START + "G91\nO1 repeat [20]\nG1 Y0.5\nO1 endrepeat\nG90\nO2 repeat [20]\nG1 Y0\nO2 endrepeat\n",
    "parameters": START + "#<y> = 0\nO1 repeat [20]\n#<y> = #<y> + 1\nG1 Y#<y>\nO1 endrepeat\n",
    "the sign of zero": START + "#<z> = 0\nO1 repeat [9]\n#<z> = -#<z>\nG1 X250 Y[#<z>] Z150\nO1 endrepeat\n",
    "pause": START + "O1 repeat [6]\nPAUSE\nG1 Y1\nG1 Y0\nO1 endrepeat\n",
    "arcs": START + "O1 repeat [8]\nG300 X260 Y10 Z150 R10\nG301 X270 Y0 Z150\nG1 X250 Y0\nO1 endrepeat\n",
    "empty body": START + "O1 repeat [30]\nO1 endrepeat\nG1 Y1\n",
    "from line": START + "O1 repeat [30]\n#<a> = 2\nG1 Y-1\nG1 Y0\nO1 endrepeat\nG1 Y[#<a>]\n",
    "a warning each pass": START + "O1 repeat [10]\nG1 Y-1 F99999\nG1 Y0\nO1 endrepeat\n",
}


def _compiled(text: str, monkeypatch, replay: bool, **options):
    executed = []
    execute = StatementExecution._execute

    def counting(self, number, *args):
        executed.append(number)
        return execute(self, number, *args)

    with monkeypatch.context() as patch:
        patch.setattr(StatementExecution, "_execute", counting)
        if not replay:
            patch.setattr(repeats, "MAX_PASS_KEPT", 0)
        compilation = compile_text(text, "job.txt", **options)
        statements = list(compilation)
    state = compilation.state
    return {
        "statements": repr(statements), "frames": [s.command.encode() for s in statements],
        "diagnostics": repr(compilation.diagnostics), "errors": compilation.error_count,
        "lines run": compilation.lines_run,
        "state": repr((state.values, state.parameters, state.relative, state.unknown_because)),
    }, len(executed)


@pytest.mark.parametrize("text", TEXTS.values(), ids=TEXTS.keys())
def test_a_replayed_pass_is_the_pass_executed(text, monkeypatch):
    for from_line in (1, text.count("\n")):
        replayed, _ = _compiled(text, monkeypatch, True, from_line=from_line)
        executed, _ = _compiled(text, monkeypatch, False, from_line=from_line)
        assert replayed == executed


@pytest.mark.parametrize("path", sorted((ROOT / "scripts").glob("*.txt")), ids=lambda p: p.name)
def test_every_script_compiles_as_before(path, monkeypatch):
    text = path.read_text(encoding="utf-8")
    assert _compiled(text, monkeypatch, True)[0] == _compiled(text, monkeypatch, False)[0]


def test_a_repeated_pass_is_not_executed_again(monkeypatch):
    text = START + "O1 repeat [1000]\nG1 Y-1\nG1 Y0\nO1 endrepeat\n"
    (replayed, run), (executed, run_all) = _compiled(text, monkeypatch, True), _compiled(text, monkeypatch, False)
    assert replayed == executed and len(executed["frames"]) == 2001
    assert run_all == 2000 and run <= 6  # two or three passes run, the rest replayed


def test_the_sign_of_zero_and_a_pause_are_never_replayed(monkeypatch):
    _, run = _compiled(TEXTS["the sign of zero"], monkeypatch, True)
    assert run == 1 + 9 * 2  # #<z> = 0, then every pass (0.0 == -0.0, but the frames differ)
    _, run = _compiled(TEXTS["pause"], monkeypatch, True)
    assert run == 6 * 3


def test_a_replay_stops_where_the_line_limit_is_passed(monkeypatch):
    monkeypatch.setattr(compiler, "MAX_LINES_RUN", 101)
    monkeypatch.setattr(repeats, "MAX_LINES_RUN", 101)
    text = START + "O1 repeat [40]\nG1 Y-1\nG1 Y0\nO1 endrepeat\n"  # runs out of lines inside a pass
    replayed, _ = _compiled(text, monkeypatch, True)
    executed, _ = _compiled(text, monkeypatch, False)
    assert replayed == executed and "E012" in replayed["diagnostics"]


def test_a_block_whose_passes_differ_stops_keeping_them(monkeypatch):
    kept = []
    init = repeats._Pass.__init__

    def counting(self, *args):
        kept.append(1)
        init(self, *args)

    monkeypatch.setattr(repeats._Pass, "__init__", counting)
    text = START + "G91\nO1 repeat [100]\nG1 Y0.5\nO1 endrepeat\n"  # every pass moves on
    assert len(list(compile_text(text, "job.txt"))) == 101
    assert len(kept) == 1 + repeats.MAX_PASS_MISSES


_LINES = ["G1 Y-1", "G1 Y0", "G1 Y[#<a>]", "G1 X250 Y[#<a> * 0] Z150", "#<a> = #<a> + 1", "#<a> = -#<a>", "#<a> = 0",
          "G91", "G90", "PAUSE", "G4 P10", "G1 Z151 F2000", "G300 X260 Y10 Z150 R10\nG301 X270 Y0 Z150", "G1 Y0.5 Q1"]


@st.composite
def _bodies(draw, depth=0):
    lines = []
    for _ in range(draw(st.integers(0, 4))):
        if depth < 2 and draw(st.integers(0, 3)) == 0:
            label = f"L{depth}{len(lines)}"
            lines += [f"O<{label}> repeat [{draw(st.integers(0, 6))}]", *draw(_bodies(depth + 1)), f"O<{label}> endrepeat"]
        else:
            lines.append(draw(st.sampled_from(_LINES)))
    return lines


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(_bodies(), st.integers(1, 12))
def test_random_blocks_compile_as_when_every_pass_runs(monkeypatch, body, from_line):
    text = START + "#<a> = 0\nO<top> repeat [7]\n" + "\n".join(body) + "\nO<top> endrepeat\nG1 Y2\n"
    assert _compiled(text, monkeypatch, True, from_line=from_line)[0] == \
        _compiled(text, monkeypatch, False, from_line=from_line)[0]
