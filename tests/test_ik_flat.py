"""The one flat IK solver gives the enumeration's answers bit for bit (issues 11 and 13).

armctl/core/kinematics.py's ``_solve`` replaced two copies of the closed form (the enumerating
``inverse``/``solutions`` the simulator used, and lint's flat ``has_solution``).  The old
enumeration is kept, test-only, in tests/ik_reference.py; here the package's ``inverse``,
``solutions`` and ``has_solution`` are held to it over random poses (reachable ones from
forward kinematics, arbitrary ones, the base-axis and J5 = 0 singularities), hints and joint
limits: the same floats (``repr``: sign of zero and int-versus-float included: the simulator's
status bytes come from these joints), the same Unreachable message.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import ik_reference
from armctl.core.kinematics import Links, Unreachable, forward, has_solution, inverse, solutions, wrap_deg
from armctl.core.kinematics_inverse import _fit, _fitted

LINKS = Links(base_height_mm=150, shoulder_offset_mm=30, upper_arm_mm=180, elbow_offset_mm=30, forearm_mm=180,
              tool_mm=60)
ZERO_OFFSETS = Links(base_height_mm=150, shoulder_offset_mm=0, upper_arm_mm=180, elbow_offset_mm=0, forearm_mm=180,
                     tool_mm=60)  # the wrist centre can sit on the base axis
LIMITS = ((-170, 170), (-90, 100), (-120, 120), (-180, 180), (-120, 120), (-360, 360))
HOME = (0.0, 0.0, 0.0, 0.0, 90.0, 0.0)

_ANGLE = st.one_of(st.sampled_from([0.0, -0.0, 90.0, -90.0, 180.0, -180.0, 45.0]), st.floats(-180, 180))
_HINT = st.one_of(st.none(), st.just(HOME), st.tuples(*(st.floats(-200, 200) for _ in range(6))))


@st.composite
def _limits(draw):
    """None, the profile's, or six random (low, high) pairs, ints or floats, some narrow."""
    kind = draw(st.sampled_from(["none", "profile", "random"]))
    if kind == "none":
        return None
    if kind == "profile":
        return LIMITS
    pairs = []
    for _ in range(6):
        low = draw(st.one_of(st.integers(-400, 180), st.floats(-400, 180)))
        pairs.append((low, low + draw(st.one_of(st.integers(0, 400), st.floats(0, 400)))))
    return tuple(pairs)


@st.composite
def _poses(draw):
    """(links, pose): forward kinematics of random joints (J5 = 0 and wrist centres on the base
    axis among them), or an arbitrary pose, often out of reach."""
    links = draw(st.sampled_from([LINKS, ZERO_OFFSETS]))
    kind = draw(st.sampled_from(["joints", "singular wrist", "arbitrary"]))
    if kind == "arbitrary":
        return links, (draw(st.floats(-450, 450)), draw(st.floats(-450, 450)), draw(st.floats(-100, 600)),
                       draw(_ANGLE), draw(_ANGLE), draw(_ANGLE))
    joints = [draw(st.one_of(st.sampled_from([0.0, 90.0, -90.0, 180.0]), st.floats(-180, 180))) for _ in range(6)]
    if kind == "singular wrist":
        joints[4] = draw(st.sampled_from([0.0, 180.0]))
    return links, tuple(forward(joints, links))


def _reference(pose, links, near, limits):
    try:
        return ik_reference.inverse(pose, links, near, limits)
    except Unreachable as error:
        return error


@settings(max_examples=700, deadline=None)
@given(_poses(), _HINT, _limits())
@example((LINKS, (600.0, 0.0, 150.0, 180.0, 0.0, 0.0)), None, LIMITS)  # out of reach
@example((LINKS, tuple(forward((0, 0, 0, 0, 90, 0), LINKS))), HOME, ((-170, 170), (5, 100)) + LIMITS[2:])  # J2
@example((ZERO_OFFSETS, (0.0, 0.0, 300.0, 180.0, 0.0, 0.0)), (30.0, 0, 0, 10.0, 90.0, 0), LIMITS)  # on the base axis
@example((LINKS, tuple(forward((0, 20, 10, 0, 0, 150), LINKS))), (0, 20, 10, -100, 0, 0),
         LIMITS[:5] + ((-10, 10),))  # J5 = 0, J6 = 150 − (−100) wrapped to −110, outside its limits
def test_inverse_is_the_enumeration_bit_for_bit(links_pose, near, limits):
    links, pose = links_pose
    expected = _reference(pose, links, near, limits)
    try:
        found = inverse(pose, links, near, limits)
    except Unreachable as error:
        assert isinstance(expected, Unreachable), (pose, expected)
        assert str(error) == str(expected)
        found_ok = False
    else:
        assert repr(found) == repr(expected), (pose, near, limits)
        found_ok = True
    if limits is not None:
        assert has_solution(pose, links, near if near is not None else (0.0,) * 6, limits) is found_ok
    assert repr(solutions(pose, links, near)) == repr(ik_reference.solutions(pose, links, near))


def test_the_examples_reach_every_branch():
    """The properties above see reachable poses, each kind of Unreachable and both singularities."""
    assert inverse((250, 0, 150, 180, 0, 0), LINKS, HOME, LIMITS)
    with pytest.raises(Unreachable, match="out of the arm's reach"):
        inverse((600, 0, 150, 180, 0, 0), LINKS, HOME, LIMITS)
    with pytest.raises(Unreachable, match=r"needs J2 = 0\.0°, outside its limits 5…100°"):
        inverse(tuple(forward((0, 0, 0, 0, 90, 0), LINKS)), LINKS, HOME, ((-170, 170), (5, 100)) + LIMITS[2:])
    on_axis = solutions((0.0, 0.0, 300.0, 180.0, 0.0, 0.0), ZERO_OFFSETS, (30.0, 0, 0, 0, 90, 0))
    assert on_axis and all(math.isclose(abs(s[0] - 30.0) % 180.0, 0.0, abs_tol=1e-9) for s in on_axis)  # J1 = hint's
    flat_wrist = solutions(tuple(forward((0, 20, 10, 0, 0, 0), LINKS)), LINKS, (0, 0, 0, 25.0, 0, 0))
    assert any(s[3] == pytest.approx(25.0) and s[4] == 0.0 for s in flat_wrist)  # J5 = 0: J4 = hint's


@settings(max_examples=400, deadline=None)
@given(st.one_of(st.sampled_from([0.0, -0.0, 180.0, -180.0, 360.0, -540.0]), st.floats(-720, 720)),
       st.one_of(st.sampled_from([0.0, -0.0, 179.0, -179.0]), st.floats(-400, 400)),
       st.one_of(st.none(), st.sampled_from([(-0.0, 0.0), (0, 0), (-170, 170), (-360, 360)]),
                 st.tuples(st.floats(-400, 400), st.floats(0, 400)).map(lambda p: (p[0], p[0] + p[1]))))
def test_fitted_is_fit_of_the_wrapped_angle(angle, hint, limits):
    """The solver's fast path for one joint is ``_fit`` of the wrapped angle, sign of zero included."""
    assert repr(_fitted(angle, hint, limits)) == repr(_fit(wrap_deg(angle), hint, limits))


def test_the_ik_benchmark_runs_as_the_readme_shows_it():
    """benchmarks/ik_speed.py (the README's IK figures) in a fresh process, one pass."""
    root = Path(__file__).resolve().parents[1]
    assert "benchmarks/ik_speed.py" in (root / "README.md").read_text(encoding="utf-8")
    done = subprocess.run([sys.executable, str(root / "benchmarks" / "ik_speed.py"), "--repeats", "1"],
                          capture_output=True, text=True, timeout=60, cwd=root)
    assert done.returncode == 0, done.stderr
    names = [line.split("  ")[0] for line in done.stdout.splitlines()]
    assert names == ["inverse, path", "inverse, mixed", "has_solution, path", "has_solution, mixed"], done.stdout
    assert all("calls/s" in line for line in done.stdout.splitlines())
