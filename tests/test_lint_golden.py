"""Lint's findings do not change when lint gets faster (issue 13: "findings must not change").

tests/data/lint/golden/diagnostics.json holds what lint reported — every finding, its place,
severity, message and hint — on a fixed corpus (every_rule.txt, scripts/*.txt and
golden/geometry.txt: random poses in and around the reach, attitudes, G54 origins, G6 and POSE
hints, G91 loops, arcs), recorded before the kinematics fast path and the reach cache existed
(tests/data/lint/golden/record.py).  A fast path that gave one different answer shows here.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

GOLDEN = Path(__file__).parent / "data" / "lint" / "golden"


def _recorder():
    spec = importlib.util.spec_from_file_location("golden_record", GOLDEN / "record.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


RECORDER = _recorder()
EXPECTED = json.loads((GOLDEN / "diagnostics.json").read_text(encoding="utf-8"))


def test_the_corpus_is_the_recorded_one():
    assert sorted(EXPECTED) == sorted(f"{script} {profile or 'default'}" for script, profile in RECORDER.CORPUS)
    assert sum(len(found["diagnostics"]) for found in EXPECTED.values()) > 900  # the corpus does find things


@pytest.mark.parametrize("script, profile", RECORDER.CORPUS, ids=[f"{s}-{p or 'default'}" for s, p in RECORDER.CORPUS])
def test_lint_reports_what_it_reported_before(script, profile):
    found = json.loads(json.dumps(RECORDER.diagnostics(script, profile)))  # tuples → lists, as recorded
    expected = EXPECTED[f"{script} {profile or 'default'}"]
    assert found["diagnostics"] == expected["diagnostics"]
    assert found == expected
