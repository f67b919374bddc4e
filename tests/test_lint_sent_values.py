"""A finding judges the value the frame carries (32-bit floats, H1), not the digits written: at the
edge of a range, ``S2500.00001`` is sent as exactly 2500 and is not outside 500…2500 (found by an
adversarial review of issue 10: lint refused it, compile sent it)."""

from __future__ import annotations

from importlib import resources

from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.lint.engine import lint_lines
from armctl.host.profile import load_profile
from armctl.core.protocol import as_f32

EDGE = st.one_of(
    st.floats(min_value=2499.99, max_value=2500.01), st.floats(min_value=499.99, max_value=500.01),
    st.sampled_from([2500.00001, 2500.0001, 499.99999, 500.0, 2500.0]),
)


def _users_profile(tmp_path_factory):
    path = tmp_path_factory.mktemp("profile") / "arm.toml"
    path.write_bytes(resources.files("armctl.data").joinpath("default_profile.toml").read_bytes())
    return load_profile(path)  # the user's own numbers: a PWM finding is an error


@settings(max_examples=150, deadline=None)
@given(value=EDGE)
def test_the_pwm_range_is_judged_on_the_value_sent(tmp_path_factory, value):
    profile = _users_profile(tmp_path_factory)
    text = f"G1 X250 Y0 Z150 A180 B0 C0 S{value!r} F3000\n"
    codes = {d.code for d in lint_lines(text.splitlines(), "job.txt", profile).diagnostics}
    sent = as_f32(value)
    outside = not 500.0 <= sent <= 2500.0
    assert (bool(codes & {"L302", "E005"})) == outside, (value, sent, codes)
