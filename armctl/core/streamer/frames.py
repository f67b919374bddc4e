"""What the streamer keeps of each frame written, and the names of its reasons.

Strategy: plain records.  A ``SentFrame`` carries everything every part of the streamer needs
to know of one frame — its planned segment, when it left the wire, the estimate's end, the time
bound's deadlines, what its path can prove — so the parts share frames, not each other's state.
``WaitReason`` and ``Evidence`` say why a decision went the way it did, as data.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from operator import attrgetter

from ..motion import Segment
from ..protocol import Command
from .constants import POSITION_TOLERANCE_MM


class WaitReason(StrEnum):
    """What held the last write back (``Streamer.write_reason``)."""

    READY = "ready"  # nothing: the frame may go now
    CAPACITY = "capacity"  # rule (a): the FIFO bound is reached; only new evidence allows a write
    LEAD = "lead"  # rule (b): the motion waiting behind the move in progress fills the lead
    WIRE = "wire"  # the previous frame is still leaving the host at the line's rate
    IN_ORDER = "in order"  # rule (c): a control frame acting on arrival waits until the queue is known done


class Evidence(StrEnum):
    """What last advanced the lower bound of frames consumed (``Streamer.bound_evidence``)."""

    POSITION = "position"  # two agreeing X/Y/Z reports on the path of a later frame
    JOINTS = "joints"  # two agreeing joint-half reports on a later joint or still frame
    TIME = "time"  # even an arm slowest_factor times slower than the model has finished them
    AT_REST = "at rest"  # the caller saw the arm at rest at the last target (confirm_all_done)
    PROGRAM_ENDED = "program ended"  # the caller saw the arm work after a PROGRAM landed, then rest (job_program.ProgramWait)


@dataclass(slots=True)
class SentFrame:
    """A frame on its way to, in, or through the connector's FIFO.

    Set once when it is written (``Streamer.wrote``), except the fields one part keeps up to
    date, each by that part alone: ``est_end_s`` the estimate; ``certain_end_s`` and
    ``chain_end_s`` the time bound; ``may_be_cleared`` the ledger; ``seen`` the at-rest proof
    (``Streamer.confirm_all_done``, and the caller, armctl/core/job.py)."""

    index: int
    command: Command
    segment: Segment
    tag: object  # the caller's reference, e.g. the script line
    wire_end_s: float  # its last byte left the host
    est_end_s: float = 0.0  # the estimate: when the arm finishes it
    certain_end_s: float = 0.0  # the time bound: it has surely finished by then (arm-running time)
    chain_end_s: float = 0.0  # the time bound as a chain of frames (a G300's certain end is its G301's)
    group_index: int = -1  # the first frame of its group: an arc's G301 finishes with its G300
    xyz_tolerance_mm: float = POSITION_TOLERANCE_MM  # how near its path an X/Y/Z must be to match
    # False for a move that starts where only the profile's unverified kinematics put an earlier
    # frame of the job (a Cartesian move at a joint move's end, a joint move at a Cartesian one's):
    # the arm's path is not the planned one, and it may pass within tolerance of the next frame's
    # path, so a sighting may count on it (the earliest claim) but never past it; the time bound,
    # with ``TimeBound.allowance_s``, confirms a line or a joint move (never an arc).
    path_known: bool = True
    unknown_start_s: float = 0.0  # ``TimeBound.allowance_s`` of its segment, reckoned once at write
    motion_before_s: float = 0.0  # the model's motion time of every frame written before it
    # ... of those whose length the plan knows: a move whose start only the profile's unverified
    # kinematics know (``unknown_start_s``) may be any shorter, so the loss checks' least motion
    # counts it as none
    sure_before_s: float = 0.0
    sure_s: float = 0.0  # its own share of ``sure_before_s`` for the frames after it (0 with an allowance)
    timing_known: bool = True  # False: its time may be any (``TimeBound.moves_e_from_the_start``): no pace from it
    seen: bool = False  # the arm at rest at its target proved it ran (``evidence.ran_at_rest``)
    by_time: bool = False  # counted consumed by time alone (``Ledger.consume_one``; ``Ledger.proven_run`` recounts it)
    may_be_cleared: bool = False  # queued when a RESET CONNECTOR may have cleared it (``Streamer.cleared``)
    judged_by_start: bool = False  # a straight move the not-begun sign judges by its start (``evidence.standing_at_start``)
    # ... a long one whose refusal it cannot see, or a short one whose refusal the plan foresees
    # (``Sightings.may_refuse``), so only reports prove it ran (``Ledger.prove_ran``):
    # two on its path past its start, or two inside the next line's path away from its end and
    # off the way from its start (``Sightings.note_runs``, which counts them on every such move)
    needs_run_proof: bool = False
    moved_seen: int = 0
    last_on_path: tuple | None = None  # the last report on its path: number, window start, waiting (``run_seen``)
    near: list | None = None  # the pending frames whose path may meet its own (``run_proof.near_frames``)
    near_through: int = -1  # ... of those written up to this one
    inside_seen: int = 0


def where(sent: SentFrame) -> str:
    """A frame as the user knows it: its script line when the tag has one."""
    line = getattr(sent.tag, "line", None)
    return f"frame {sent.index + 1}" if line is None else f"frame {sent.index + 1} (line {line})"


est_end = attrgetter("est_end_s")  # a frame's estimated end: the key the queue is searched by
