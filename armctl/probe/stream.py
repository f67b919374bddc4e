"""The status stream as the probe reads it: the arm's period and rotation of kinds, and when each
frame read was built.

Strategy: the arm builds a status frame every period, in a fixed rotation of kinds — each up to
the profile's ``[connector] status_jitter_ms`` after its place on the period, never before (its
own loop may be late); the host reads each one late — by its reader's wake-up, or by a USB adapter's latency timer, which hands
bytes over in ticks (16 ms by default on the common adapters) — and never early.  So each frame
read gets its slot in the stream: first by time (``_slots``: counted from the frames just
before it, which lateness cannot drift), which gives the period and the rotation
(``_rotation``); then by kind (``_kind_slots``), since lateness may spread over a whole period
(frames read together, then none for 48 ms, through a pty behind 16 ms ticks) where a kind
still tells its slot.  Through every run of frames so counted the period is a line, and no frame
was built later than the jitter after the line through any frame near it (``latest_built_s``): taking the second
earliest such line, widened by the period's possible tilt, bounds each frame's build time
without ever putting it before the frame was built — but for the one case ``_kind_slots``
names, a corrupted kind byte it cannot tell from lateness.  That bound takes the reads'
lateness out of a timed move's samples (armctl/probe/motion.py), which had taken it for the
arm's start delay; a stretch whose kinds do not count its slots keeps its read times.
"""

from __future__ import annotations

from ..core.profile_model import Connector
from ..core.protocol import STATUS_PERIOD_S, STATUS_ROTATION
from .plan import LIKELY, SURE, UNSURE, Finding

SLOT_ANCHORS = 20  # frames a status frame's slot is counted from (``_slots``)
SINGLE_GAP = 1.75  # spacings up to this many median spacings count as one step at first (``_slots``)
MIN_STREAM_GAPS = 100  # frames read before a frame's build time is bounded (``latest_built_s``)
ANCHOR_SLOTS = 18  # a frame's build time is bounded by the frames this many slots either side
MIN_ANCHORS = 18  # ... when at least this many of them were counted (``latest_built_s``)
STEP_SLACK = 1.3  # slots a frame's step may differ from the time since the frame before (``_kind_slots``)


def status_stream(probe):
    """The period (the line of the frames' times over their slots: ``_slots``) and the rotation of kinds."""
    frames = probe.seen.frames
    read = _read(frames, 20)
    if read is None:
        return Finding("status_stream", f"{STATUS_PERIOD_S * 1000:g} ms, {len(STATUS_ROTATION)} kinds", None,
                       f"only {len(frames)} status frames read", UNSURE)
    times, _, _, period_s, rotation = read
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
        slots, period_s = again, _slope([(again, times)])[0]
    return slots, period_s


def _read(frames, min_gaps: int):
    """What the stream read so far says (``status_stream``, ``latest_built_s``): its frames' times and
    kinds, their slots and period by time (``_slots``) and the rotation (``_rotation``); None with
    fewer than ``min_gaps`` spacings between them."""
    times = [t for t, _ in frames]
    gaps = sorted(b - a for a, b in zip(times, times[1:]) if b > a)
    if len(gaps) < min_gaps:
        return None
    slots, period_s = _slots(times, gaps[len(gaps) // 2])
    kinds = [frame.KIND for _, frame in frames]
    return times, kinds, slots, period_s, _rotation(slots, kinds)


def _slope(runs) -> tuple[float, float]:
    """The least-squares slope of time over slot through ``runs`` (each a (slots, times) pair, with
    its own intercept; both rising: it is positive), and its spread Σ(slot − its run's mean)²."""
    spread = lean = 0.0
    for slots, times in runs:
        mean_slot, mean_t = sum(slots) / len(slots), sum(times) / len(times)
        spread += sum((slot - mean_slot) ** 2 for slot in slots)
        lean += sum((slot - mean_slot) * (t - mean_t) for slot, t in zip(slots, times))
    return lean / spread, spread


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


def latest_built_s(frames, first_s: float, jitter_s: float = Connector.status_jitter_ms / 1000) -> dict[int, float]:
    """The latest time each frame read from ``first_s`` on can have been built, by ``id`` of its
    entry in ``frames`` (``Seen.frames``: the stream read so far, in order); a frame missing from
    the answer keeps its read time (module docstring).  Each frame's slot is counted by its kind
    (``_kind_slots``), the period is the line through every run of counted frames, and each frame
    is bounded by the frames of its run within ``ANCHOR_SLOTS`` slots of it, plus ``jitter_s``:
    how much later than its place on the period the arm may build a frame (the profile's
    ``[connector] status_jitter_ms``; the document's reading by default)."""
    read = _read(frames, MIN_STREAM_GAPS)
    if read is None:
        return {}
    times, kinds, _, period_s, cycle = read
    if cycle is None or len(set(cycle)) < len(cycle):
        return {}  # (a kind twice in the rotation: a kind does not tell its slot)
    runs = [run for run in _kind_slots(times, kinds, cycle, period_s) if len(run) >= MIN_ANCHORS]
    if sum(len(run) for run in runs) < MIN_STREAM_GAPS:
        return {}
    # The period: the slope of time over slot within the runs (each its own intercept) ...
    period_s, spread = _slope([([s for _, s in run], [times[i] for i, _ in run]) for run in runs])
    # ... known to within what the frames' lateness can tilt it: lateness within the residuals'
    # range moves that slope by at most the range × Σ(slots above their run's mean − it) / spread,
    # allowed twice over for every slot between two frames.
    residual = {i: times[i] - s * period_s for run in runs for i, s in run}
    late_range_s = max(max(residual[i] for i, _ in run) - min(residual[i] for i, _ in run) for run in runs)
    above = sum(s - m for run in runs for m in [sum(s for _, s in run) / len(run)] for _, s in run if s > m)
    margin_s = 2 * late_range_s * above / spread
    built: dict[int, float] = {}
    for run in runs:
        low = high = 0
        for k, (i, slot) in enumerate(run):
            while run[low][1] < slot - ANCHOR_SLOTS:
                low += 1
            high = max(high, k)
            while high + 1 < len(run) and run[high + 1][1] <= slot + ANCHOR_SLOTS:
                high += 1
            if times[i] < first_s or high - low + 1 < MIN_ANCHORS:
                continue  # (too many frames around it lost or not counted: its read time stands)
            # no frame was built later than ``jitter_s`` after the line through any frame near it
            # (reads are never early, nor builds before their place on the period) but one: the
            # second earliest, so one miscounted frame alone never moves the bound
            line_s = sorted(residual[j] + abs(slot - s) * margin_s for j, s in run[low:high + 1])[1]
            built[id(frames[i])] = min(times[i], line_s + slot * period_s + jitter_s)
    return built



def _kind_slots(times: list[float], kinds: list[int], cycle: list[int], period_s: float) -> list[list]:
    """Runs of frames whose kinds count their slots, each a list of (index, slot).  A frame's
    step from the one before is the one its kind says (the next place in ``cycle``, or further
    on past lost frames) nearest the time between them: lateness cannot mislead a count mod the
    rotation.  A step more than ``STEP_SLACK`` slots from its time ends the run and begins the
    next (runs' slots are not comparable), and a frame belongs to a run only when both its
    steps — from the frame before, to the frame after — were checked: a run's first and last
    frames are left out.  So a corrupted kind byte (a known kind for another) leaves its frame
    out, except where the slot it claims is one off and a frame next to it was lost: its steps
    are then a slot off their times, as lateness alone may make them.  Such a frame's own bound
    may then be up to a period early; as a bound for the others it moves nothing
    (``latest_built_s`` never bounds a frame by one other alone)."""
    place = {kind: i for i, kind in enumerate(cycle)}
    length = len(cycle)

    def step(j: int, j_slot: int, i: int):
        elapsed = (times[i] - times[j]) / period_s
        n = (place[kinds[i]] - j_slot) % length or length
        n += length * max(0, round((elapsed - n) / length))
        return j_slot + n if abs(n - elapsed) <= STEP_SLACK else None

    runs: list[list] = []
    run: list = []
    for i, kind in enumerate(kinds):
        if kind not in place:
            continue
        slot = step(*run[-1], i) if run else None
        if slot is None:
            runs.append(run[1:-1])  # (the first one's step before and the last one's after were not checked)
            run = [(i, place[kind])]
        else:
            run.append((i, slot))
    runs.append(run[1:-1])
    return [run for run in runs if run]
