"""A virtual clock's waits: the link drives a ``sim://?clock=virtual`` port from event to event.

Strategy: the simulated port implements virtual time through one interface (armctl/sim/
protocol_sim.py): ``next_event_s()`` — the clock's reading when the next status burst has
reached the host — and ``advance_to(t) -> bytes`` — the clock moved there and the bytes that
arrived by then; and, for the simulator's quiet stretches (nothing happens in it but status
frames), ``virtual_status_run`` (the steps of the next bursts timed ahead, changing nothing),
``status_frames`` (their frames, a batch at a time) and ``commit_status_run`` (the steps read).
A wait jumps to the next burst and reads it at the model time it lands; a caller that names
which frames are news (``news(frames, times)``: the place of the first, or None — the job
runner) is woken only by those, and the quiet stretches are then read as runs of steps timed
ahead, their frames built and decoded a batch at a time and handed to ``news`` in one call, the
run committed as far as it was read: the same frames at the same model times as one burst at a
time, without the per-burst machinery; a wait asks for a run only once a burst of it has
passed without news (the steps right after a write or news are seldom quiet) and two status
periods are left (``VIRTUAL_RUN_LEFT_S``).  The steps of a run past the frame that was news, and
the frames built for them, stay the simulator's next while nothing else touches the port (the
run's arithmetic from the committed state is the same from any step on): the next news wait
that starts where that frame was read reads them (cut at its own end) instead of timing and
building them again, and a write forgets them (``forget``) — at most a batch of frames built
for nothing a write.
"""

from __future__ import annotations

from typing import Callable

from ..core.protocol import STATUS_PERIOD_S, STATUS_SIZE

VIRTUAL_MIN_STEP_S = 1e-6
# A news wait reads the simulator's quiet stretches as runs of steps timed ahead, from this
# many, doubling while no frame is news, up to the most: 32 measured best of 8…512 for the
# 20-minute job of benchmarks/virtual_run.py (8 was best before the steps were kept).
VIRTUAL_RUN_FRAMES_MIN = 32
VIRTUAL_RUN_FRAMES_MAX = 512
# A wait times a run (a tail kept apart) only once one of its bursts has passed without news,
# and only while this much is left before its end.  Right after a write or a frame that was news
# the simulator's next step is seldom a quiet one (the frame written lands, a segment ends), and
# a run timed for less than two status periods holds one frame at most, which a burst reads for
# less; a burst reads the same frames at the same times.  The 24,000-frame job of
# benchmarks/virtual_run.py (a write every 50 ms) asked for 62,520 runs, 47,003 of them empty and
# most of the rest one step long (15,594 frames read in 15,556 runs); with one period left
# 20,092, 17,434 empty (2,658 frames in 2,658 runs), 2 % less CPU; with two 12,968, 10,348 empty
# (2,620 frames in 2,620 runs), 1 % less again; the 20-minute job unchanged.
VIRTUAL_RUN_LEFT_S = 2 * STATUS_PERIOD_S
# The frames of a run are built and decoded a batch at a time, ahead of reading them: the
# simulator's code and the engine's each run in a batch (the 20-minute job: 0.82 -> 0.75 s of
# CPU).  A batch is as many frames as the waits read of the run before it, at least
# ``VIRTUAL_BUILD_FIRST`` — after a write, when the wait may end at once — else
# ``VIRTUAL_BUILD_FRAMES``, and at most that.  The 24,000-frame job writes every 50 ms and its
# waits end at their first frames (the next kind-4 frame, when the FIFO bound holds it): at 64 a
# batch it built 96,837 frames to read 15,594 (then 15,594, 3 % of its CPU; it reads 2,620 by
# runs now: ``VIRTUAL_RUN_LEFT_S``); the 20-minute job writes 13 frames and reads long runs, 64 a
# batch as before (from 1 or 8 after every wait, not only after a write, it cost 8 % more).  A
# write wastes at most a batch (the tail it forgets).
VIRTUAL_BUILD_FRAMES = 64
VIRTUAL_BUILD_FIRST = 1
UNMERGED_FRAMES_MAX = 4096  # frames of virtual runs held before they are merged into the state

News = Callable[[list, list], "int | None"]


class VirtualWaits:
    """The waits of one link on a virtual clock (``Link.wait``), and the run steps kept between them."""

    def __init__(self, link) -> None:
        self.link = link
        # The unread steps of the last status run (the run, the first unread, the clock time of
        # the last read, the frames built for it so far, the frames of the run read by the waits
        # so far): still the simulator's next steps while nothing else touched the port and the
        # clock is where that run left it
        self.tail: tuple[list, int, float, list, int] | None = None
        self.wrote = True  # a write came since the last run was read: the next wait may end soon

    def forget(self) -> None:
        """Something else touched the port (a write): the steps kept are not its next any more."""
        self.tail = None
        self.wrote = True

    def wait(self, until_s: float | None, news: News | None = None) -> None:
        """Jump to the next status burst or to ``until_s``, at least a microsecond on (a wait
        computed as a difference of nearly equal floats could otherwise leave the clock where it
        is, and the caller asking again forever); with ``news``, on past every frame that is not
        news, burst after burst, until one is or ``until_s`` comes."""
        clock = self.link.clock
        end_s = max(until_s, clock.now_s + VIRTUAL_MIN_STEP_S) if until_s is not None else None
        run_frames = VIRTUAL_RUN_FRAMES_MIN
        tail, self.tail = self.tail, None
        quiet = False  # a burst of this wait has passed without news: a run may be worth timing
        while True:  # burst after burst (or run after run) until one holds news, or end_s
            if news is not None and (tail is not None or quiet and (
                    end_s is None or end_s - clock.now_s >= VIRTUAL_RUN_LEFT_S)):
                run, built, read_before = self._next_run(tail, end_s, run_frames)
                tail = None
                if run:
                    read, is_news = self._take_run(run, built, news, read_before)
                    if is_news or (end_s is not None and clock.now_s >= end_s):
                        return
                    if read == len(run):
                        run_frames = min(2 * run_frames, VIRTUAL_RUN_FRAMES_MAX)  # quiet: look further ahead
                        continue
                    # a frame the run could not decode (never on a clean line): the ordinary way reads it
            if self._burst(end_s, news) or (end_s is not None and clock.now_s >= end_s):
                return
            quiet = True

    def _next_run(self, tail, end_s: float | None, run_frames: int) -> tuple[list, list, int]:
        """The simulator's next quiet steps, the frames built for them already and how many of
        the run were read before: the steps kept from the last run when the clock is where it
        left them (cut at ``end_s``), else up to ``run_frames`` timed afresh (none when the next
        step is not a quiet one)."""
        if tail is not None and tail[2] == self.link.clock.now_s:
            run = _steps_by(tail[0], tail[1], end_s)
            return run, tail[3][tail[1]:tail[1] + len(run)], tail[4]
        return self.link.port.virtual_status_run(end_s, VIRTUAL_MIN_STEP_S, run_frames), [], 0

    def _burst(self, end_s: float | None, news: News | None) -> bool:
        """Read the next status burst (``next_event_s``, at least ``VIRTUAL_MIN_STEP_S`` on and
        never past ``end_s``, then ``advance_to``); whether it ends the wait."""
        # two calls of the one interface, not a shortcut: a port that wraps the simulator (an
        # adapter's buffer in tests/test_probe_rates.py) implements these two and must be asked
        port, now_s = self.link.port, self.link.clock.now_s
        next_s = port.next_event_s()
        step_to = now_s + VIRTUAL_MIN_STEP_S if next_s is None else max(next_s, now_s + VIRTUAL_MIN_STEP_S)
        if end_s is not None and end_s < step_to:
            step_to = end_s
        data = port.advance_to(step_to)
        return bool(data) and self.link.take(data, news)

    def _take_run(self, run: list, built: list, news: News, read_before: int = 0) -> tuple[int, bool]:
        """A run of quiet steps timed ahead (``virtual_status_run``: one status frame each, with
        the clock time it is read at), read as bursts are: the frames (built by ``status_frames``
        and decoded by ``StatusReader.decode_frames``, a batch at a time, as many as were read
        of the run before it (``read_before`` by earlier waits), at least ``VIRTUAL_BUILD_FIRST``
        after a write and ``VIRTUAL_BUILD_FRAMES`` else, at most ``VIRTUAL_BUILD_FRAMES``; the first ones may be ``built`` already) go to ``news`` a batch at a time, the clock moved to
        the last one it took, up to the first that is news (a run never goes past the wait's
        end).  The frames read are committed to the simulator whatever happens (``news`` may
        raise: Ctrl-C; every frame it was given then counts as read), so none is read twice.
        Returns (frames read, whether the last was news)."""
        link = self.link
        port, advance, unmerged = link.port, link.clock.advance_to, link.unmerged
        read = 0
        try:
            with link.lock:
                try:
                    while read < len(run):
                        if read == len(built):  # the next frames built and decoded a batch at a time
                            first = VIRTUAL_BUILD_FIRST if self.wrote else VIRTUAL_BUILD_FRAMES
                            built += self._build(run[read:read + min(VIRTUAL_BUILD_FRAMES, max(first, read_before + read))])
                        frames = built[read:]
                        whole = built[-1] is not None
                        if not whole:  # a frame that could not be decoded: the ordinary way reads it
                            frames.pop()
                            if not frames:
                                return read, False
                        times = [step[0] for step in run[read:read + len(frames)]]
                        place = len(frames) - 1  # if it raises: the engine had them all, or is gone
                        try:
                            place = news(frames, times)
                        finally:
                            taken = len(frames) if place is None else place + 1
                            advance(times[taken - 1])
                            read += taken
                            unmerged += zip(frames, times[:taken])  # merged into the state when it is read
                        if place is not None:
                            if read < len(run):
                                self.tail = (run, read, times[taken - 1], built, read_before + read)
                            return read, True
                        if not whole:
                            return read, False
                    return read, False
                finally:  # the counts for the whole run at once, before the lock is let go
                    self.wrote = False
                    link.counted(read, read * STATUS_SIZE)
        finally:
            port.commit_status_run(run, read)

    def _build(self, steps: list) -> list:
        """The frames of ``steps`` decoded (a None last where one could not be: never on a clean line)."""
        batch = self.link.port.status_frames(steps)
        decoded = self.link.reader.decode_frames(batch)
        if len(decoded) < len(batch):
            decoded.append(None)
        return decoded


def _steps_by(run: list, start: int, end_s: float | None) -> list:
    """The steps of ``run`` from ``start`` on that end by ``end_s`` (their clock times grow)."""
    stop = len(run)
    if end_s is not None:
        for k in range(start, stop):
            if run[k][0] > end_s:
                stop = k
                break
    return run[start:stop]
