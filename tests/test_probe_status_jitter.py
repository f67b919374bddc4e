"""An arm whose own loop builds each status frame a little after its place on the period
(``[connector] status_jitter_ms``, impersonated by ``sim://?status_jitter_ms=``): the probe's bound
on when each frame read was built (armctl/probe/stream.py ``latest_built_s``) allows it, so a
frame built late is never timed before it was built (tests/test_review3.py has the synthetic
stream; these go through the simulator in virtual time, where a frame is read as it is built)."""

from __future__ import annotations

import dataclasses

import pytest

from armctl.core.protocol import STATUS_PERIOD_S
from armctl.errors import ProfileError
from armctl.host.profile import load_profile, parse_profile
from armctl.probe import motion
from armctl.probe.stream import latest_built_s
from test_probe import probe_sim

pytestmark = pytest.mark.timeout(60)


def _profile(jitter_ms: float):
    profile = load_profile()
    return dataclasses.replace(profile, connector=dataclasses.replace(profile.connector, status_jitter_ms=jitter_ms))


@pytest.mark.parametrize("seed", [0, 7])
def test_frames_built_up_to_3_ms_late_are_never_timed_before_they_were_built(seed):
    probe, _, _ = probe_sim(f"status_jitter_ms=3&seed={seed}", profile=_profile(3.0))
    frames = probe.seen.frames  # read on a virtual clock: each timed when it was built
    assert len(frames) > 1000
    late_ms = [(t - k * STATUS_PERIOD_S - frames[0][0]) * 1000 for k, (t, _) in enumerate(frames)]
    assert 2.5 < max(late_ms) - min(late_ms) <= 3.0  # the simulated arm builds them up to 3 ms late
    bound = latest_built_s(frames, frames[0][0], 0.003)
    assert len(bound) > 0.9 * len(frames)
    early_ms = [(t - bound[id(entry)]) * 1000 for entry in frames for t in [entry[0]] if id(entry) in bound]
    assert max(early_ms) <= 1e-6, f"a frame put {max(early_ms):.3f} ms before it was built"
    # the rule for an arm that builds every frame on its period puts them up to ~3 ms early
    exact = latest_built_s(frames, frames[0][0], 0.0)
    assert max((entry[0] - exact[id(entry)]) * 1000 for entry in frames if id(entry) in exact) > 2.0


def test_the_probe_bounds_its_samples_with_the_profiles_jitter(monkeypatch):
    used = []

    def recorded(frames, first_s, jitter_s):
        used.append(jitter_s)
        return latest_built_s(frames, first_s, jitter_s)

    monkeypatch.setattr(motion, "latest_built_s", recorded)
    probe, _, _ = probe_sim("status_jitter_ms=2.5", motion=True, profile=_profile(2.5))
    assert probe.finding("speed_factor").value == pytest.approx(1.0, abs=0.01)
    assert used and set(used) == {0.0025}


def test_the_setting_is_read_and_checked():
    assert load_profile().connector.status_jitter_ms == 1.0  # the document's "every 30 ms", in whole ms
    assert parse_profile({"connector": {"status_jitter_ms": 4}}).connector.status_jitter_ms == 4
    with pytest.raises(ProfileError, match="status_jitter_ms"):
        parse_profile({"connector": {"status_jitter_ms": 16}})
