"""The status stream as the probe reads it: the arm's period and rotation of kinds, and when each
frame read was built.

Strategy: the arm builds a status frame every period, in a fixed rotation of kinds; the host
reads each one late — by its reader's wake-up, or by a USB adapter's latency timer, which hands
bytes over in ticks (16 ms by default on the common adapters) — and never early.  So each frame
read gets its slot in the stream (``_slots``: counted from the frames just before it, which
lateness cannot drift), the slots give the period (the least-squares line of time over slot)
and the rotation (``_rotation``), and within a stretch whose every frame's kind fits the
rotation at its slot — the slots proven right — the earliest frame against that line bounds
them all: no frame was built later than the line through it (``latest_built_s``).  That bound
removes the read's lateness from a timed move's samples (armctl/probe/motion.py) without ever
putting a sample before the time its frame was built; a stretch whose kinds do not fit keeps
its read times.
"""

from __future__ import annotations

from ..core.protocol import STATUS_PERIOD_S, STATUS_ROTATION
from .plan import LIKELY, SURE, UNSURE, Finding

SLOT_ANCHORS = 20  # frames a status frame's slot is counted from (``_slots``)
SINGLE_GAP = 1.75  # spacings up to this many median spacings count as one step at first (``_slots``)


def status_stream(probe):
    """The period (the line of the frames' times over their slots: ``_slots``) and the rotation of kinds."""
    frames = probe.seen.frames
    times = [t for t, _ in frames]
    gaps = sorted(b - a for a, b in zip(times, times[1:]) if b > a)
    if len(gaps) < 20:
        return Finding("status_stream", f"{STATUS_PERIOD_S * 1000:g} ms, {len(STATUS_ROTATION)} kinds", None,
                       f"only {len(frames)} status frames read", UNSURE)
    slots, period_s = _slots(times, gaps[len(gaps) // 2])
    kinds = [frame.KIND for _, frame in frames]
    rotation = _rotation(slots, kinds)
    documented = f"{STATUS_PERIOD_S * 1000:g} ms, {len(STATUS_ROTATION)} kinds {list(STATUS_ROTATION)}"
    value = {"period_ms": round(period_s * 1000, 3), "rotation": rotation}
    evidence = f"{len(frames)} frames over {times[-1] - times[0]:.1f} s"
    confidence = SURE if rotation is not None else LIKELY
    shown = f"{period_s * 1000:.2f} ms, " + (f"{len(rotation)} kinds {rotation}" if rotation else "rotation unclear")
    return Finding("status_stream", documented, shown, evidence, confidence, value)


def _slots(times: list[float], step_s: float) -> tuple[list[int], float]:
    """Each frame's slot in the stream (a lost frame leaves its slot empty) and the period.
    Read on the wall clock a frame's time is late by the reader's wake-up or an adapter's latency
    timer (up to 16 ms), and the median spacing is off by as much as that jitter's grain (30.3 ms
    for 30.0 through armctl sim --pty): slots counted from the first frame at that step drift by
    one every hundred frames, and a rotation read from them is garbage.  So each frame's slot is
    counted from the frames just before it (the median of what each of the last ``SLOT_ANCHORS``
    says: one late frame moves nothing, and the period's error cannot add up) at a period first
    the mean of the spacings of one step (up to ``SINGLE_GAP`` median spacings: two frames read at
    once, 0 ms, then a 48 ms wait, are two such steps), then the least-squares line of time over
    slot, until the slots stay put.  A lateness that spreads over a whole period may still leave
    the rotation unclear: it is then not stated."""
    single = [after - before for before, after in zip(times, times[1:]) if after - before <= SINGLE_GAP * step_s]
    period_s = sum(single) / len(single)  # (two frames read at once, then a long wait: their mean is one step)
    slots: list[int] = []
    for _ in range(8):
        again = [0]
        for i in range(1, len(times)):
            said = sorted(again[j] + (times[i] - times[j]) / period_s for j in range(max(0, i - SLOT_ANCHORS), i))
            again.append(max(again[-1] + 1, round(said[len(said) // 2])))
        if again == slots:
            break
        slots, period_s = again, _slope(again, times)
    return slots, period_s


def _slope(slots: list[int], times: list[float]) -> float:
    """The least-squares slope of ``times`` over ``slots`` (both rising: it is positive)."""
    mean_slot, mean_t = sum(slots) / len(slots), sum(times) / len(times)
    spread = sum((slot - mean_slot) ** 2 for slot in slots)
    return sum((slot - mean_slot) * (t - mean_t) for slot, t in zip(slots, times)) / spread


def _rotation(slots, kinds) -> list[int] | None:
    """The shortest cycle of kinds that ≥ 95 % of the frames (by slot) agree with; each place in
    it is the kind most frames at that place showed (a lost frame leaves its slot empty)."""
    by_slot = dict(zip(slots, kinds))
    start = min(by_slot)
    for length in range(1, 33):
        pairs = [(kind, by_slot.get(slot + length)) for slot, kind in by_slot.items() if slot + length in by_slot]
        if len(pairs) >= 2 * length and sum(a == b for a, b in pairs) >= 0.95 * len(pairs):
            places: list[dict] = [{} for _ in range(length)]
            for slot, kind in by_slot.items():
                place = places[(slot - start) % length]
                place[kind] = place.get(kind, 0) + 1
            if not all(places):
                return None
            cycle = [max(place, key=place.get) for place in places]
            first = cycle.index(min(cycle))  # shown from its lowest kind, as the document lists them
            return cycle[first:] + cycle[:first]
    return None
