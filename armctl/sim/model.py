"""The simulated arm: line, connector, executor and status output, driven by events.

Strategy (sans-I/O, after h11): the caller owns the clock.  ``write(data, now_s)`` puts host
bytes on the line; the connector frames them at once (framing needs no timing) and each frame
gets the exact time its last byte lands.  ``advance(now_s)`` then processes, in time order,
every event up to ``now_s`` — a frame landing, a segment ending, a status frame falling due —
and returns the status bytes whose last bit has reached the host.  ``next_event_time()`` lets
a virtual-time driver jump straight to the next moment anything changes.  Nothing here loops
over bytes or ticks over time: a 1000-frame job costs about 1000 landings, 1000 executions and
one status frame per 30 ms of arm time.  Its records of what happened (frames received, executions)
keep the most recent ``connector.HISTORY_FRAMES`` entries (or up to twice that) plus counters, so memory stays flat
however long a virtual run is.

A virtual-time host that reads on past frames that are no news to it (armctl/host/link.py) asks for
the quiet stretches between events as runs (``status_run``): the timing of each step it would
take, one status frame each, computed ahead without changing anything; it builds a step's frame
only when it reads it (``status_frame``) and commits the steps it read (``commit_status_run``),
so a 20-minute job costs its status frames and little else (benchmarks/virtual_run.py).

At one instant, events run in this order: segment ends (freeing slots), then frames landing,
then the status frame (so it reports the state after both).

Time never runs backwards: a ``write`` or ``advance`` with a time before the model's current
time is taken to happen at the current time.  No time, threading or serial imports here.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from dataclasses import dataclass

from ..core.protocol import CONNECTOR_BUFFER_FRAMES, DEFAULT_BAUD, STATUS_PERIOD_S, STATUS_SIZE
from .connector import Connector, Framer, ReceivedFrame, decode_received
from .executor import Execution, Executor, LiveSnapshot
from .faults import StatusFaults
from .program import SdProgram
from .status import StatusEncoder, StatusSchedule
from .wire import TIME_EPSILON_S, Wire


@dataclass(frozen=True)
class SimOptions:
    """How the simulated arm and its line behave: everything a ``sim://`` URL says, parsed once
    (armctl/sim/protocol_sim.py).  ``profile``: a ``Profile``, a path to a profile TOML, or None
    for ``chosen_profile()``'s choice — the arm's speeds, limits and (``link_scale`` apart) links.

    The arm's unknowns carry the names of the profile's ``[connector]`` settings, with the
    document's readings as defaults (the packaged profile's, checked by a test): the simulated
    arm impersonates any arm a profile may describe.  It takes them from here, never from its
    profile: the profile is the host's belief, these are the arm's truth."""

    baud: int = DEFAULT_BAUD
    speed_factor: float = 1.0  # 1.3 = every motion takes 30 % longer than the model says
    control_frames: str = "queued"  # H5: control frames wait in the FIFO; "arrival": they act on landing
    fifo_frames: int = CONNECTOR_BUFFER_FRAMES  # frames accepted behind the one executing (H6)
    status_xyz_frame: str = "worktable"  # what status kind 0 reports after G54; or "robot"
    link_scale: float = 1.0  # the arm's link lengths are the profile's × this (its kinematics differ)
    status_jitter_s: float = 0.0  # each status frame is built up to this much after its place on the period
    status_loss_rate: float = 0.0
    status_corrupt_rate: float = 0.0
    noise_rate: float = 0.0
    seed: int = 0
    profile: object = None
    time_scale: float = 1.0  # speed=: the arm runs this many times faster than the wall clock
    virtual_clock: bool = False  # clock=virtual: model time moves only while the host waits
    # The line's edges, as real ones have them (read by armctl/sim/realtime.py, protocol_sim.py and
    # bridge.py): host bytes not yet on the wire are held in a buffer of this many bytes, and a
    # write blocks while it is full, as a tty's does (None: never full); the host reads status
    # bytes only at ticks this many model seconds apart, as a USB adapter's latency timer hands
    # them over (0: as each byte lands).
    write_buffer_bytes: int | None = None
    read_granularity_s: float = 0.0

    @property
    def control_on_arrival(self) -> bool:
        return self.control_frames == "arrival"

    def __post_init__(self) -> None:
        if not self.baud > 0:
            raise ValueError(f"baud must be positive, not {self.baud!r}")
        if not self.speed_factor > 0:
            raise ValueError(f"speed_factor must be positive, not {self.speed_factor!r}")
        if not self.fifo_frames > 0:
            raise ValueError(f"fifo_frames must be positive, not {self.fifo_frames!r}")
        if self.control_frames not in ("queued", "arrival"):
            raise ValueError(f"control_frames must be 'queued' or 'arrival', not {self.control_frames!r}")
        if self.status_xyz_frame not in ("worktable", "robot"):
            raise ValueError(f"status_xyz_frame must be 'worktable' or 'robot', not {self.status_xyz_frame!r}")
        if not self.link_scale > 0:
            raise ValueError(f"link_scale must be positive, not {self.link_scale!r}")
        if not 0 <= self.status_jitter_s < STATUS_PERIOD_S:
            raise ValueError(f"status_jitter_s must be 0 or more, under the period, not {self.status_jitter_s!r}")
        if self.write_buffer_bytes is not None and not self.write_buffer_bytes > 0:
            raise ValueError(f"write_buffer_bytes must be positive, not {self.write_buffer_bytes!r}")
        if not self.read_granularity_s >= 0:
            raise ValueError(f"read_granularity_s must be 0 or more, not {self.read_granularity_s!r}")


def _load_profile(profile):
    from ..host.profile import Profile, chosen_profile

    if isinstance(profile, Profile):
        return profile
    return chosen_profile(profile)  # its connector is its options': no arm's [connector] laid over


def _arm_profile(options: SimOptions):
    """The simulated arm's own profile: the options' profile with every link × ``link_scale``."""
    profile = _load_profile(options.profile)
    if options.link_scale == 1.0:
        return profile
    links = profile.links
    scaled = type(links)(**{f.name: getattr(links, f.name) * options.link_scale for f in dataclasses.fields(links)})
    return dataclasses.replace(profile, links=scaled)


class SimulatedArm:
    """The arm, its connector and both directions of the line, in virtual time."""

    def __init__(self, options: SimOptions = SimOptions(), start_s: float = 0.0) -> None:
        self.options = options
        self.profile = _arm_profile(options)
        self.now_s = start_s
        self.host_line = Wire(options.baud, keeps_bytes=False)  # host → arm: timing only
        self.arm_line = Wire(options.baud)  # arm → host: the status bytes themselves
        self.framer = Framer()
        self.connector = Connector(capacity_frames=options.fifo_frames)
        self.executor = Executor(self.profile, self.connector, options.speed_factor, options.control_on_arrival, start_s)
        self.executor.reports_robot_xyz = options.status_xyz_frame == "robot"
        self.schedule = StatusSchedule(STATUS_PERIOD_S, first_s=start_s, jitter_s=options.status_jitter_s, seed=options.seed)
        self.faults = StatusFaults(options.status_loss_rate, options.status_corrupt_rate, options.noise_rate, options.seed)
        self._status = StatusEncoder()  # status_bytes, straight from the executor
        self.status_frames_built = 0
        self._landings: deque[tuple[float, bytes]] = deque()  # frames framed, not yet landed

    # --- the host's side -----------------------------------------------------------------------

    def write(self, data: bytes, now_s: float) -> None:
        """Host bytes handed to the line at ``now_s``; they land behind any still in flight."""
        self._run_until(now_s)
        data = bytes(data)
        start_s = self.host_line.send(data, self.now_s)
        for end, frame in self.framer.feed(data):
            if frame is not None:
                self._landings.append((self.host_line.arrival_s(start_s, end), frame))

    def advance(self, now_s: float) -> bytes:
        """Run the arm up to ``now_s``; the status bytes that reached the host by then."""
        self._run_until(now_s)
        return self.arm_line.take(self.now_s)

    def next_event_time(self) -> float | None:
        """When anything next changes: a frame lands, a segment ends, a status frame is built,
        or the status bytes in flight (a frame, with any noise before it) have all reached the host."""
        candidates = [self._next_internal_s(), self.arm_line.run_end_s()]
        return min((t for t in candidates if t is not None), default=None)

    def advance_until_idle(self, limit_s: float = float("inf")) -> bytes:
        """Run until every frame written has landed and nothing runs (frames may still wait,
        e.g. behind a pause), or until ``limit_s``; the status bytes produced meanwhile."""
        out = bytearray()
        while self.now_s < limit_s:
            dues = [self.executor.next_event_s()]  # None when idle or frozen by a pause
            if self._landings:
                dues.append(self._landings[0][0])
            due_s = min((t for t in dues if t is not None), default=None)
            if due_s is None:
                break
            out += self.advance(min(limit_s, due_s))
        return bytes(out)

    def next_output_time(self) -> float:
        """When the next status burst (a frame, with any noise before it) has fully reached the
        host: the one in flight, else the next frame due (a real-time reader sleeps until then)."""
        in_flight_s = self.arm_line.run_end_s()
        if in_flight_s is not None:
            return in_flight_s
        return max(self.schedule.next_s, self.arm_line.free_at_s) + STATUS_SIZE * self.arm_line.byte_s

    def host_bytes_in_flight(self, now_s: float) -> int:
        """Host bytes written but not yet fully landed at ``now_s`` (pyserial's out_waiting)."""
        return self.host_line.in_flight(max(now_s, self.now_s))

    def host_room_at_s(self, limit_bytes: int, want_bytes: int) -> float:
        """When no more than ``limit_bytes − want_bytes`` host bytes are still in flight (a buffer
        of ``limit_bytes`` then takes ``want_bytes`` more)."""
        line = self.host_line
        return line.free_at_s - max(0, limit_bytes - want_bytes) * line.byte_s

    def host_line_free_s(self) -> float:
        """When the last host byte written so far will have landed."""
        return self.host_line.free_at_s

    # --- a run of status frames, computed ahead (clock=virtual) --------------------------------

    def status_run(self, clock_s: float, end_s: float | None, min_step_s: float, max_frames: int,
                   clock_start_s: float, time_scale: float) -> list[tuple[float, int, float, float, float]]:
        """The timing of up to ``max_frames`` successive virtual-time steps, computed without
        changing anything: [(clock time, status kind, its due time, wire free, model time)],
        for as long as a step is a quiet one — the line back to the host clear, no status fault,
        no executor event and no landing due, exactly one whole status frame arriving in the
        step — and ends by ``end_s``.  ``status_frame`` builds a step's frame (the executor's
        state cannot change in a quiet stretch); ``commit_status_run`` makes the first n steps so.

        A step is a burst of ``protocol_sim.Serial``'s virtual time (``next_event_s``, then
        ``advance_to``): the clock (``clock_s``; model time = (clock − ``clock_start_s``) ×
        ``time_scale``) moves to when the next status frame has reached the host (``next_output_time``), at least ``min_step_s`` on, and the model
        advances there (``_run_until``: the frame is built at its due time and sent).  The same
        arithmetic, operation by operation, so the same frames at the same times to the last
        bit; only the per-step machinery (candidate lists, the wire's runs, the lock, a burst
        decoded apart) is gone.  The caller stops reading at a frame that is news to it; the
        link keeps the steps past it (and the frames it built ahead for them, a batch at a time)
        for its next wait, so a write throws away at most a batch of built frames."""
        run: list[tuple[float, int, float, float, float]] = []
        arm_line = self.arm_line
        if arm_line._runs or self.faults.active or self.schedule.jitter_s:
            return run  # (a frame built off its period: the full loop, through ``StatusSchedule.next_s``)
        landings, executor, schedule = self._landings, self.executor, self.schedule
        quiet_until_s = executor.next_event_s()
        if landings and (quiet_until_s is None or landings[0][0] < quiet_until_s):
            quiet_until_s = landings[0][0]
        first_s, period_s, rotation, count = schedule.first_s, schedule.period_s, schedule.rotation, schedule.count
        byte_s, free_s, model_s = arm_line.byte_s, arm_line.free_at_s, self.now_s
        burst_s, executor_s, kinds = STATUS_SIZE * byte_s, executor.now_s, len(rotation)
        # max(a, b) written ``b if b > a else a`` (what max returns, without a call), the next
        # frame's due time computed once for both steps, no end or event as +inf
        end_s = math.inf if end_s is None else end_s
        quiet_until_s = math.inf if quiet_until_s is None else quiet_until_s
        status_s, stop = first_s + count * period_s, count + max_frames  # StatusSchedule.next_s
        while count < stop:
            start_s = free_s if free_s > status_s else status_s  # Wire.send's start
            wait_s = (start_s + burst_s - (clock_s - clock_start_s) * time_scale) / time_scale  # next_output_time
            if not wait_s > 0.0:
                wait_s = 0.0
            step_to = clock_s + (min_step_s if min_step_s > wait_s else wait_s)
            if end_s < step_to:
                break
            limit_s = (step_to - clock_start_s) * time_scale  # _run_until's limit
            if model_s > limit_s:
                limit_s = model_s
            due_by_s = limit_s + TIME_EPSILON_S
            next_status_s = first_s + (count + 1) * period_s
            if quiet_until_s <= due_by_s or status_s > due_by_s or next_status_s <= due_by_s:
                break  # an event in this step, or not exactly one status frame: the full loop
            if limit_s > executor_s:  # Executor.run_until: no event to run
                executor_s = limit_s
            next_model_s = executor_s if executor_s > limit_s else limit_s
            if (next_model_s - start_s + TIME_EPSILON_S) / byte_s < STATUS_SIZE:
                break  # not all of it arrived (Wire.take: its floor below STATUS_SIZE, i.e. this)
            free_s = start_s + burst_s  # (every status frame is STATUS_SIZE bytes)
            model_s, clock_s = next_model_s, step_to
            run.append((step_to, rotation[count % kinds], status_s, free_s, model_s))
            count += 1
            status_s = next_status_s
        return run

    def status_frame(self, kind: int, at_s: float) -> bytes:
        """The status frame of ``kind`` built at ``at_s`` (a step of a ``status_run``)."""
        return self._status.encode(kind, self.executor, at_s)

    def status_frames(self, steps: list) -> list[bytes]:
        """``status_frame`` of each step of a ``status_run`` in ``steps``, in one call (the link
        builds a batch at a time: ``VirtualWaits._take_run``)."""
        return self._status.encode_steps(self.executor, steps)

    def commit_status_run(self, run: list[tuple[float, int, float, float, float]], frames: int) -> None:
        """Make the first ``frames`` steps of ``run`` (``status_run``, nothing changed since) so:
        their status frames built, sent and read, the model at the last one's time."""
        if frames <= 0:
            return
        free_s, model_s = run[frames - 1][3:]
        self.schedule.count += frames
        self.status_frames_built += frames
        self.arm_line.free_at_s = free_s
        self.arm_line.bytes_sent += STATUS_SIZE * frames
        executor = self.executor
        executor.now_s = max(executor.now_s, model_s)
        self.now_s = model_s

    # --- the event loop ------------------------------------------------------------------------

    def _next_internal_s(self) -> float:
        times = [self.schedule.next_s]
        if self._landings:
            times.append(self._landings[0][0])
        executor_s = self.executor.next_event_s()
        if executor_s is not None:
            times.append(executor_s)
        return min(times)

    def _run_until(self, now_s: float) -> None:
        limit_s = max(now_s, self.now_s)
        due_by_s = limit_s + TIME_EPSILON_S
        executor, landings, schedule = self.executor, self._landings, self.schedule
        next_executor_s = executor.next_event_s
        while True:
            executor_s = next_executor_s()
            landing_s = landings[0][0] if landings else None
            status_s = schedule.next_s
            if executor_s is not None and executor_s <= due_by_s and (
                landing_s is None or executor_s <= landing_s) and executor_s <= status_s:
                executor.run_until(executor_s)
            elif landing_s is not None and landing_s <= due_by_s and landing_s <= status_s:
                _, raw = landings.popleft()
                executor.land(decode_received(self.connector.next_index(), landing_s, raw), landing_s)
            elif status_s <= due_by_s:
                self._emit_status(status_s)
            else:
                break
        executor.run_until(limit_s)
        self.now_s = max(limit_s, executor.now_s)

    def _emit_status(self, at_s: float) -> None:
        frame = self._status.encode(self.schedule.pop(), self.executor, at_s)
        self.arm_line.send(self.faults.apply(frame), at_s)
        self.status_frames_built += 1

    # --- the truth, for tests and the benchmark ------------------------------------------------

    @property
    def fifo(self) -> list[ReceivedFrame]:
        """Frames in the connector now: those executing (holding slots) then those waiting."""
        return list(self.connector.executing) + list(self.connector.queue)

    @property
    def fifo_occupancy(self) -> int:
        return self.connector.occupancy

    @property
    def peak_fifo_occupancy(self) -> int:
        return self.connector.peak_occupancy

    @property
    def frames_received(self) -> list[ReceivedFrame]:
        """The well-framed frames that landed, in arrival order (``.index``, ``.accepted``): all
        of them in a run of up to ``HISTORY_FRAMES`` or more, else the most recent."""
        return self.connector.received

    @property
    def frames_dropped(self) -> int:
        return self.connector.dropped

    @property
    def dropped_indexes(self) -> list[int]:
        """Arrival indexes of the frames dropped (the most recent, if there were very many)."""
        return self.connector.dropped_indexes

    @property
    def bad_frames(self) -> int:
        """Frames discarded for a wrong tail byte (H7)."""
        return self.framer.bad_frames

    @property
    def skipped_bytes(self) -> int:
        """Bytes skipped while hunting for a head byte (H7)."""
        return self.framer.skipped_bytes

    @property
    def execution_log(self) -> list[Execution]:
        """What the arm took, in order: every execution in a run of up to ``HISTORY_FRAMES``
        frames or more, else the most recent (``history_complete`` says which)."""
        return self.executor.log

    @property
    def history_complete(self) -> bool:
        """True while ``execution_log`` and ``frames_received`` still hold the whole run."""
        return self.executor.log.complete and self.connector.received.complete

    @property
    def pose(self):
        """The true pose now (``motion.ArmPose``: ``.cartesian`` in the worktable frame, ``.joints``)."""
        return self.executor.pose_at(self.now_s)

    def snapshot(self) -> LiveSnapshot:
        """What a status frame would report now (X/Y/Z in the worktable frame, or the robot frame
        with ``status_xyz_frame="robot"``, joints, …)."""
        return self.executor.snapshot(self.now_s)

    @property
    def paused(self) -> bool:
        return self.executor.paused

    @property
    def pwm_us(self) -> float:
        return self.pose.pwm_us[0]

    @property
    def origin_mm(self) -> tuple[float, float, float]:
        return self.executor.origin_mm

    @property
    def structure_mode(self) -> int:
        return self.executor.structure_mode

    @property
    def program(self) -> SdProgram:
        return self.executor.program

    @property
    def busy(self) -> bool:
        """True while a segment (move, delay, SD program…) runs."""
        return self.executor.busy

    @property
    def idle(self) -> bool:
        """Nothing running, nothing waiting, nothing on the line towards the arm."""
        return not self.executor.busy and not self.connector.queue and not self._landings
