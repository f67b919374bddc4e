"""The line scanner's text parsers are linear and say what the old regular expressions said.

Issue 10: a line with a 4 KB ``;`` comment containing "armctl" cost about a second of lint,
because ``;.*?\\barmctl:…`` was tried from every ``;`` (quadratic).  The references below are
the old expressions; Hypothesis checks that the linear versions agree with them on comments of
any content (lines never hold a newline: the reader splits on it).  The long-line tests bound a
regression with a subprocess timeout, not with a timed assertion.
"""

from __future__ import annotations

import re
import subprocess
import sys

from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.lint.scan import code_text, ignored_codes

_OLD_IGNORE = re.compile(r";.*?\barmctl:\s*ignore\b(?:\[([^\]]*)\])?", re.I)
_OLD_INLINE_COMMENT = re.compile(r"\([^)\n]*\)")


def reference_ignored_codes(text: str):
    match = _OLD_IGNORE.search(text)
    if match is None:
        return None
    if match.group(1) is None:
        return ()
    return tuple(code.strip().upper() for code in re.split(r"[,\s]+", match.group(1)) if code.strip())


def reference_code_text(text: str) -> str:
    return _OLD_INLINE_COMMENT.sub(lambda m: " " * len(m.group()), text).split(";", 1)[0]


# fragments that matter to the parsers, mixed with any other characters (no newline)
FRAGMENTS = st.sampled_from([";", " ", "\t", "armctl", "ARMCTL", "armctl:", "ignore", "IGNORE", "ignores", "[", "]",
                             ",", "L203", "e", "(", ")", "G1 X10", "_", "armctl: ignore[", "K", "\u212a", "\u0130"])
LINES = st.lists(st.one_of(FRAGMENTS, st.text(st.characters(blacklist_characters="\n"), max_size=3)),
                 max_size=30).map("".join)


@settings(max_examples=400, deadline=None)
@given(LINES)
def test_ignored_codes_agrees_with_the_reference(text):
    assert ignored_codes(text) == reference_ignored_codes(text)


@settings(max_examples=400, deadline=None)
@given(LINES)
def test_code_text_agrees_with_the_reference(text):
    assert code_text(text) == reference_code_text(text)


def test_known_comments():
    assert ignored_codes("G1 X500 ; armctl: ignore[L103, l2]") == ("L103", "L2")
    assert ignored_codes("G1 X500 ; armctl: ignore") == ()
    assert ignored_codes("G1 X500 ; armctl says hello") is None
    assert ignored_codes("G1 X500 (armctl: ignore)") is None  # only a ; comment counts
    assert code_text("G1 (a) X1 (b ; c) Y2 ; Z3") == "G1     X1         Y2 "


def test_lines_full_of_semicolons_and_brackets_lint_quickly_in_a_fresh_process(tmp_path):
    # 100 lines, each with a finding (L203) and a 4 KB comment of ";armctl" and "(": about 45 s
    # before the fix; a timeout, not a timed assertion, bounds it
    comment = ";" * 3000 + "armctl " * 50 + "(" * 300  # under the 4,096-character line limit
    script = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F3000\n" + f"G1 F30 {comment}\n" * 100
    path = tmp_path / "long_comments.txt"
    path.write_text(script)
    result = subprocess.run([sys.executable, "-m", "armctl", "lint", str(path)], capture_output=True, text=True,
                            timeout=15)
    assert result.returncode == 0 and "Found 100 warnings" in result.stdout


# --- L401's parameter bookkeeping: the ASCII fast path against the general one ------------------

PARAMETER_FRAGMENTS = st.sampled_from(["#<a>", "#<A>", "#<b_1>", "#<_x>", "#<", ">", "#", "=", " = ", "N10 ", "n7",
                                       "[", "]", "+", "1.5", "(", ")", ";", " ", "\t", "G1 X", "O1 repeat", "\u212a"])
PARAMETER_LINES = st.lists(st.one_of(PARAMETER_FRAGMENTS, st.text(st.characters(blacklist_characters="\n"), max_size=2)),
                           max_size=12).map("".join)


def _bookkeeping(scanner):
    return ({name: (span.line, span.column, span.end_column, span.text) for name, span in scanner._defined.items()},
            scanner._used - {""})


@settings(max_examples=400, deadline=None)
@given(st.lists(PARAMETER_LINES, max_size=8), st.sampled_from(["\n", "\r\n", ""]))
def test_ascii_parameter_path_agrees_with_the_general_one(texts, ending):
    """``LineScanner.watch`` (its inline path on ASCII lines) notes the same assignments,
    at the same columns, and the same reads as ``_parameters_in`` on every line's code."""
    from armctl.lint.scan import LineScanner

    fast = LineScanner("f.txt", lambda: {}, lambda *finding: None)
    assert list(fast.watch(text + ending for text in texts)) == [text + ending for text in texts]
    general = LineScanner("f.txt", lambda: {}, lambda *finding: None)
    for number, text in enumerate(texts, 1):
        text = (text + ending).rstrip("\r\n")  # as the scanner always had it
        general._parameters_in(number, text, code_text(text))
    assert _bookkeeping(fast) == _bookkeeping(general)
    assert list(fast.unused_parameters()) == list(general.unused_parameters())


def test_ascii_parameter_path_known_lines():
    from armctl.lint.scan import LineScanner

    scanner = LineScanner("f.txt", lambda: {}, lambda *finding: None)
    lines = ["#<Spare> = 1 (#<inside>)\n", "N5 (why) #<B> = [#<c> + 1] ; #<after>\n", "#<b> = [#<b> + 1]\n",
             "G1 X#<C> (#<d>\n"]
    list(scanner.watch(lines))
    assert _bookkeeping(scanner) == ({"spare": (1, 1, 9, "#<Spare> = 1 (#<inside>)"),
                                      "b": (2, 10, 14, "N5 (why) #<B> = [#<c> + 1] ; #<after>")},
                                     {"c", "b", "d"})
