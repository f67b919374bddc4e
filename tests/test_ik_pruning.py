"""The IK solver's shortcuts for the simulator's status frames change no answer (issue 11).

armctl/core/kinematics.py's ``_solve`` (``inverse``: the simulator asks it of every joints status
frame, 13,372 times in benchmarks/virtual_run.py's 20-minute job) fits a joint with
``_fitted``'s first test inline and asks ``_fitted`` for the rest, with the cost so far and the
best's: ``_fitted`` answers None without ``_fit`` when no answer of ``_fit`` could keep the
solution below the best.  Held here: that bound is never wrong (``_fitted`` against ``_fit``
over arbitrary angles, hints, limits and costs), and ``inverse`` along the simulator's own
kind of path (a line at one attitude, the profile's limits, the home pose as the hint: the
case where almost every joint is pruned so) is the enumeration's, bit for bit.
"""

from __future__ import annotations

import math

from hypothesis import example, given, settings
from hypothesis import strategies as st

import ik_reference
from armctl.core.kinematics import Kinematics, Unreachable, wrap_deg
from armctl.core.kinematics_inverse import _fit, _fitted
from armctl.host.profile import default_profile

_PROFILE = default_profile()
_LIMITS = tuple(tuple(pair) for pair in _PROFILE.joint_limits_deg)
_HOME = tuple(_PROFILE.poses[0])


@settings(max_examples=600, deadline=None)
@given(st.one_of(st.sampled_from([0.0, -0.0, 180.0, -180.0, 179.999999, 360.0, -540.0]), st.floats(-720, 720)),
       st.one_of(st.sampled_from([0.0, -0.0, 90.0, 179.0, -179.0]), st.floats(-400, 400)),
       st.one_of(st.none(), st.sampled_from([(-170, 170), (-120, 120), (-360, 360), (-0.0, 0.0)]),
                 st.tuples(st.floats(-400, 400), st.floats(0, 400)).map(lambda p: (p[0], p[0] + p[1]))),
       st.one_of(st.just(0.0), st.floats(0, 1e5)),
       st.one_of(st.just(math.inf), st.floats(0, 2e5)))
@example(179.5, 0.0, (-170, 170), 0.0, 1e-3)  # the other J1: pruned without _fit
@example(0.0, 0.0, (-170, 170), 0.0, 1e-3)  # the hint itself: never pruned
def test_fitted_prunes_only_what_cannot_win(angle, hint, limits, cost, bound):
    """``_fitted`` is ``_fit`` of the wrapped angle, or None only where that answer is None or
    brings ``cost`` to ``bound`` or beyond — the very test ``_solve`` drops a solution by."""
    exact = _fit(wrap_deg(angle), hint, limits)
    found = _fitted(angle, hint, limits, cost, bound)
    if found is None:
        assert exact is None or not cost + (exact - hint) ** 2 < bound, (exact, cost, bound)
    else:
        assert repr(found) == repr(exact)
    assert repr(_fitted(angle, hint, limits)) == repr(exact)  # no bound: no pruning


def test_fitted_does_prune():
    """The shortcut is taken (a test of a bound that never cuts would pass vacuously)."""
    assert _fit(179.5, 0.0, (-170, 170)) is None and _fitted(179.5, 0.0, (-170, 170), 0.0, 1e-3) is None
    assert _fit(-170.0, 170.0, (-360, 360)) == 190.0  # fits a turn on, 20° from the hint
    assert _fitted(-170.0, 170.0, (-360, 360), 0.0, 1e-3) is None
    assert _fitted(-170.0, 170.0, (-360, 360), 0.0, 20.0 ** 2 + 1.0) == 190.0


@settings(max_examples=400, deadline=None)
@given(st.floats(150, 320), st.floats(-200, 200), st.floats(0, 350),
       st.sampled_from([(180.0, 0.0, 0.0), (180.0, -3.508354649267438e-15, 0.0), (90.0, 45.0, 30.0),
                        (180.0, 20.0, -90.0)]),
       st.sampled_from([_HOME, (0.0, 20.0, 30.0, 0.0, 40.0, 0.0), (170.0, 0.0, 0.0, 180.0, 90.0, 300.0)]))
@example(250.0, -3.3212762860600265, 150.0, (180.0, 0.0, 0.0), _HOME)  # a status frame of virtual_run's job
def test_inverse_along_a_path_is_the_enumeration(x, y, z, attitude, hint):
    """The simulator's case, both limits and none: the same floats as tests/ik_reference.py."""
    pose = (x, y, z, *attitude)
    for limits in (_LIMITS, None):
        try:
            expected = repr(ik_reference.inverse(pose, _PROFILE.links, hint, limits))
        except Unreachable as error:
            expected = str(error)
        kinematics = Kinematics(_PROFILE.links, limits, _HOME)
        try:
            found = repr(kinematics.inverse(pose, hint))
        except Unreachable as error:
            found = str(error)
        assert found == expected, (pose, hint, limits)


def _joints_by_inverse(kinematics, pose, hint):
    """ArmPose.joints' rule as it was written before ``Kinematics.joints_of``: ``inverse``
    inside the limits, else without them, else the hint."""
    try:
        return kinematics.inverse(pose, hint)
    except Unreachable:
        try:
            return kinematics.inverse(pose, hint, respect_limits=False)
        except Unreachable:
            return hint


@settings(max_examples=400, deadline=None)
@given(st.floats(-450, 450), st.floats(-450, 450), st.floats(-100, 600),
       st.tuples(st.floats(-180, 180), st.floats(-180, 180), st.floats(-180, 180)),
       st.one_of(st.just(_HOME), st.tuples(*(st.floats(-200, 200) for _ in range(6)))),
       st.sampled_from([_LIMITS, None, ((-10, 10),) * 6]))
@example(250.0, 0.0, 150.0, (180.0, 0.0, 0.0), _HOME, _LIMITS)  # inside the limits
@example(250.0, 0.0, 150.0, (180.0, 0.0, 0.0), _HOME, ((-10, 10),) * 6)  # reachable only outside them
@example(900.0, 0.0, 150.0, (180.0, 0.0, 0.0), _HOME, _LIMITS)  # out of reach: the hint itself
def test_joints_of_is_inverse_with_its_fallbacks(x, y, z, attitude, hint, limits):
    """``Kinematics.joints_of`` (ArmPose.joints, every joints status frame) is the same floats as
    ``inverse`` with the fallbacks it replaced, and the very hint object when nothing reaches."""
    kinematics = Kinematics(_PROFILE.links, limits, _HOME)
    pose = (x, y, z, *attitude)
    found, expected = kinematics.joints_of(pose, hint), _joints_by_inverse(kinematics, pose, hint)
    assert repr(found) == repr(expected)
    assert (found is hint) == (expected is hint)


@settings(max_examples=200, deadline=None)
@given(st.floats(-450, 450), st.floats(-450, 450), st.floats(-100, 600),
       st.tuples(st.sampled_from([0.0, -0.0, 180.0, -180.0, 90.0]), st.sampled_from([0.0, -0.0, 45.0]),
                 st.sampled_from([0.0, -0.0, 30.0])),
       st.sampled_from([_LIMITS, None, ((-10, 10),) * 6]))
@example(0.0, 0.0, 150.0, (180.0, 0.0, 0.0), _LIMITS)  # on the base axis: J1 is the hint's
@example(900.0, 0.0, 150.0, (180.0, 0.0, 0.0), _LIMITS)  # out of reach: the hint itself
def test_answers_kept_by_the_object_are_the_solver_s_for_those_very_bits(x, y, z, attitude, limits):
    """``can_take`` and ``joints_of`` give an answer found before again (``Kinematics._answers``):
    asked twice, and with 0.0 and -0.0 swapped (equal, but a different question for atan2), each
    answer is the one a fresh object computes — and the caller's own hint when nothing reaches."""
    kept = Kinematics(_PROFILE.links, limits, _HOME)
    signed = tuple(-v if v == 0.0 else v for v in (x, y, z, *attitude))
    for pose in ((x, y, z, *attitude), signed, (x, y, z, *attitude), signed):
        for hint in (_HOME, tuple(-v if v == 0.0 else v for v in _HOME), (0.0, 10.0, -20.0, 0.0, 90.0, 0.0)):
            fresh = Kinematics(_PROFILE.links, limits, _HOME)
            assert kept.can_take(pose, hint) is fresh.can_take(pose, hint)
            found, expected = kept.joints_of(pose, hint), fresh.joints_of(pose, hint)
            assert repr(found) == repr(expected)
            assert (found is hint) == (expected is hint)
