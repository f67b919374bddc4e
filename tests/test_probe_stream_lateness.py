"""The probe reads the status stream late — behind a USB adapter's latency timer (16 ms by
default on the common adapters), or the reader's wake-ups — and took that lateness for the arm's
start delay: ``speed_tolerance`` 1.42 in virtual time behind 16 ms ticks, 1.92 through
``armctl sim --pty`` at ``read_granularity_ms=16`` (mean start delay 18.3 ms), where the arm's
is 1.05: every job then ran with a time bound for an arm up to twice slower (the README's pick
repeated 300 times: 835 s of arm time instead of 603).  armctl/probe/stream.py bounds when each
frame read was built; these tests hold it to its promise: never before the frame was built.
"""

from __future__ import annotations

import math
import random

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from armctl.core.protocol import STATUS_ROTATION
from armctl.probe.stream import latest_built_s
from test_probe_review import probe_late

pytestmark = pytest.mark.timeout(60)


class _Frame:
    def __init__(self, kind: int) -> None:
        self.KIND = kind


def _stream(seed: int, count: int, tick_s: float, jitter_s: float, loss: float, bad_kinds: float):
    """A stream read late: (read time, frame) pairs, and each frame's true build time.  A bad
    kind (a corrupted byte naming another kind) is put only where neither neighbour is lost nor
    has a bad kind: the one case ``_kind_slots`` documents it cannot tell from lateness is a kind
    one slot off next to a lost frame, and a bad kind ends a run as a lost frame does (seed
    1802718217, 1476 frames, jitter 3.37 ms, bad kinds 0.03: kinds 102, 103 read as 100, 102, the
    second put 23.8 ms before it was built; hypothesis drew such a stream now and then)."""
    rng = random.Random(seed)
    period_s = 0.030 * (1 + rng.uniform(-1e-4, 1e-4))
    phase_s = rng.uniform(0, 1)
    kept = [k for k in range(count) if rng.random() >= loss]
    kept_set, bad = set(kept), set()  # (a bad kind next to another is as a lost neighbour: one slot off, it ends a run)
    frames, built = [], []
    for k in kept:
        built_s = phase_s + k * period_s
        read_s = math.ceil(built_s / tick_s) * tick_s + rng.uniform(0, jitter_s)
        kind = STATUS_ROTATION[k % len(STATUS_ROTATION)]
        if rng.random() < bad_kinds and {k - 1, k + 1} <= kept_set and k - 1 not in bad:
            kind = rng.choice(STATUS_ROTATION)
            bad.add(k)
        frames.append((read_s, _Frame(kind)))
        built.append(built_s)
    return frames, built


@settings(max_examples=150, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32), count=st.integers(150, 1500), tick_ms=st.sampled_from([0.001, 1, 4, 16, 20]),
       jitter_ms=st.floats(0, 20), loss=st.sampled_from([0.0, 0.05, 0.2]), bad_kinds=st.sampled_from([0.0, 0.01, 0.03]))
@example(seed=1802718217, count=1476, tick_ms=0.001, jitter_ms=3.3724627651853467, loss=0.0, bad_kinds=0.03)
def test_no_frame_is_put_before_it_was_built(seed, count, tick_ms, jitter_ms, loss, bad_kinds):
    frames, built = _stream(seed, count, tick_ms / 1000, jitter_ms / 1000, loss, bad_kinds)
    bound = latest_built_s(frames, frames[0][0])
    early = [(built_s - bound[id(entry)]) * 1000 for entry, built_s in zip(frames, built)
             if id(entry) in bound and bound[id(entry)] < built_s - 1e-9]
    assert not early, f"{len(early)} frames put before they were built, by up to {max(early):.3f} ms"
    assert all(bound[id(entry)] <= entry[0] for entry in frames if id(entry) in bound)  # never later than read


def test_a_clean_stream_read_in_16_ms_ticks_is_bounded_within_two_ms():
    frames, built = _stream(1, 1500, 0.016, 0.0, 0.05, 0.0)
    bound = latest_built_s(frames, frames[-300][0], 0.0)  # (built on the period exactly: no jitter allowed)
    late = [(bound[id(entry)] - built_s) * 1000 for entry, built_s in zip(frames, built) if id(entry) in bound]
    raw = [(entry[0] - built_s) * 1000 for entry, built_s in zip(frames[-300:], built[-300:])]
    assert len(late) >= 290
    assert sum(late) / len(late) < 2.0 < 6.0 < sum(raw) / len(raw)  # (8 ms read late on average)


def test_the_probe_behind_a_16_ms_adapter_measures_the_arms_tolerance():
    probe = probe_late(0.016, motion=True)
    tolerance = probe.finding("speed_tolerance")
    # before: "speed_tolerance 1.42 … mean start delay 8.3 ms" (the reads' lateness); now the
    # longest start delay left is ~2 ms of it (1.09), where an arm with none reads 1.05; the
    # document's 1 ms of status jitter, allowed since (``status_jitter_ms``), adds 1 ms: 1.14
    assert tolerance.value <= 1.15, tolerance.evidence
    assert probe.finding("speed_factor").value == pytest.approx(1.0, abs=0.01)


def test_the_tolerance_covers_the_longest_start_delay_measured(tmp_path):
    """An arm that takes 10 ms before every command: the joint moves measure that start delay
    (10.6 ms) and the linear moves less (6.4 ms: their fit's intercept runs ~5 ms low even on an
    arm with none, found by the review).  The mean (8.5 ms) gave t = 1.43 where the time bound's
    slack per frame, (t − 1) × 20 ms, needs t ≥ 1.5 to cover 10 ms; the largest covers it.  Since
    the probe states the wait (command_overhead_s, which the model then adds to every command),
    the tolerance covers the longest start delay left after it."""
    from armctl.core.streamer import FRAME_SLACK_S, SLOWEST_ARM_FACTOR

    arm = tmp_path / "arm.toml"
    arm.write_text("[timing]\ncommand_overhead_s = 0.010\n")
    probe = probe_late(1e-9, options=f"profile={arm}", motion=True)
    tolerance, waited = probe.finding("speed_tolerance"), probe.finding("command_overhead_s")
    assert waited.value == 0.010, waited.evidence
    left_s = max(waited.details["start_delay_s"]) - waited.value
    assert (tolerance.value - 1) * FRAME_SLACK_S / (SLOWEST_ARM_FACTOR - 1) >= left_s, tolerance.evidence
