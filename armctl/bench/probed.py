"""The host's profile for a scenario's arm "with a probe": ``armctl probe``'s own core run
against that same simulated arm, in virtual time, its findings laid over the profile the way
``armctl probe --write`` and armctl.toml do.

Strategy: nothing here knows the answer.  A fresh ``SimulatedArm`` built from the scenario's
``SimOptions`` is probed by the pure ``Probe`` (armctl/probe/plan.py) with motion allowed (a
user who ran ``armctl probe`` and said yes); this module is only its host — it jumps the clock
from event to event as the benchmark's harness does.  The values ``--write`` would put in
armctl.toml (``report.to_write``) go through ``profile.with_connector``, the same call that reads
an armctl.toml's ``[connector]`` table, so the bench's "probed" host is the one a user gets.
A probe costs a fraction of a second of wall time; it is cached per arm (``SimOptions``).
"""

from __future__ import annotations

from functools import lru_cache

from ..probe import build_probe
from ..probe.plan import Write
from ..probe.report import to_write
from ..host.profile import Profile, with_connector
from ..core.protocol import StatusReader
from ..sim.model import SimOptions, SimulatedArm, _load_profile

PROBE_SOURCE = "armctl probe (bench, virtual time)"
PROBE_TIME_LIMIT_S = 600.0  # arm seconds: the probe takes ≤ 3 minutes at 9600 baud (issue 9)
MIN_STEP_S = 1e-6


class ProbeFailed(RuntimeError):
    """The probe did not finish on the scenario's arm (a bench defect, not a run outcome)."""


@lru_cache(maxsize=None)
def probed_settings(options: SimOptions) -> tuple[tuple[str, object], ...]:
    """What ``armctl probe --yes --write`` finds on an arm with ``options`` (key, value) pairs."""
    arm = SimulatedArm(options)
    host_profile = _load_profile(options.profile)  # the host's belief, before the probe
    probe = build_probe(host_profile, options.baud, arm.now_s, motion=True, virtual_clock=True)
    reader = StatusReader()
    now = arm.now_s
    while now < PROBE_TIME_LIMIT_S:
        for frame in reader.feed(arm.advance(now)):
            probe.feed(frame, now)
        action = probe.next_action(now)
        if action is None:
            break
        if isinstance(action, Write):
            arm.write(action.frame, now)
            continue
        upcoming = [t for t in (arm.next_event_time(), action.until_s) if t is not None]
        now = max(min(upcoming), now + MIN_STEP_S)
    if not probe.done or probe.stopped is not None or probe.interrupted:
        why = probe.stopped or f"not done after {PROBE_TIME_LIMIT_S:g} s of arm time"
        raise ProbeFailed(f"the probe did not finish on {options}: {why}")
    return tuple(sorted(to_write(probe).items()))


def probed_profile(options: SimOptions) -> Profile:
    """The host's profile after ``armctl probe`` on this arm: ``options.profile`` (unscaled links:
    the host's belief) with the probe's ``[connector]`` findings laid over it."""
    return with_connector(_load_profile(options.profile), dict(probed_settings(options)), PROBE_SOURCE)


def unprobed_profile(options: SimOptions) -> Profile:
    """The host's profile without a probe: ``options.profile`` as it is (the document's defaults)."""
    return _load_profile(options.profile)
