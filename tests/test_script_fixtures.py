"""Example scripts in tests/data/scripts/ compile as their comments say."""

from __future__ import annotations

from pathlib import Path

from armctl.core.protocol import AccelLinearMove, ArcStart, GoToPose, JointMove, LinearMove, MCode
from armctl.script import compile_file

DATA = Path(__file__).parent / "data" / "scripts"


def test_pick_and_place_compiles_to_the_expected_frames():
    job = compile_file(DATA / "pick_and_place.txt")
    statements = list(job)
    assert job.ok, [d.render() for d in job.diagnostics]
    kinds = [type(s.command) for s in statements]
    assert kinds[:2] == [JointMove, LinearMove]
    assert len(statements) == 2 + 3 * 10 + 2
    assert kinds[-2:] == [MCode, GoToPose]
    arcs = [s.command for s in statements if isinstance(s.command, ArcStart)]
    assert [a.x_mm for a in arcs] == [200, 240, 280]  # #<tray_x> advances each iteration
    lifts = [s for s in statements if s.relative]
    assert [s.command.z_mm for s in lifts] == [120, 120, 120]  # 20 + (120 - 20)
    accelerated = [s.command for s in statements if isinstance(s.command, AccelLinearMove)]
    assert {(a.mode, a.accel_mm_s2, a.speed1_mm_min) for a in accelerated} == {(0, -800, 1200)}
    assert [s.loop for s in statements if s.line == 16] == [(0,), (1,), (2,)]


def test_resuming_after_the_loop():
    job = compile_file(DATA / "pick_and_place.txt", from_line=29)
    assert [s.code for s in job] == ["M5", "POSE"] and job.ok
