"""The frames every job in scripts/ sends on several sim:// arm variants are the ones recorded
before the one-pipeline redesign (issue 23: behaviour unchanged).  benchmarks/digests.py records
and explains them; this runs the same check in the suite, one test per job and variant."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))
import digests  # noqa: E402  (benchmarks/ is not a package)

KEPT = json.loads((BENCHMARKS / "digests.json").read_text(encoding="utf-8"))["frames"]


@pytest.mark.parametrize("case", sorted(KEPT))
def test_the_frames_sent_are_the_ones_recorded(case):
    stem, variant = case.split("@")
    assert digests.frames_digest(f"{stem}.txt", digests.VARIANTS[variant]) == KEPT[case]


def test_every_job_and_variant_is_recorded():
    assert set(KEPT) == {f"{p.stem}@{v}" for p in digests.SCRIPTS.glob("*.txt") for v in digests.VARIANTS}
