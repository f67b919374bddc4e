"""The arm profile as values: frozen dataclasses of limits, speeds, PWM, poses, links, timing and the connector.

Strategy: what a checked profile *is*, apart from how it is read: ``Profile`` and its sections
are frozen, and every number knows where it came from (``Profile.source_of``: the provenance
constants below).  armctl/core/profile_schema.py checks TOML-shaped data, armctl/core/profile_build.py
builds these from it, armctl/host/profile.py (the façade) finds and loads them.  No I/O.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from functools import cached_property

from .kinematics import Kinematics, Links

GRIPPER_STATES = ("open", "closed")
FIXED_POSES = ("0", "1", "2", "3")

# Where a profile's number came from (Profile.source_of); a user's file is named by its path.
ILLUSTRATIVE = "illustrative"  # the packaged default's guess: nobody measured it
PROTOCOL = "protocol"  # a range the protocol itself fixes (PROTOCOL.md), true for every arm
PROBE = "probe"  # measured on the arm
DOCUMENT = "document"  # a [connector] default: the vendor document's reading (an H-decision)
MEASURED_ON = "measured_on"  # armctl.toml's [connector]: the arm its values belong to (armctl probe --write)
# Keys of the packaged default that are the protocol's own ranges, not guesses about an arm.
PROTOCOL_KEYS = frozenset({"pwm.range_us", "pwm.channels", "speed.max_accel_mm_s2"})


@dataclass(frozen=True)
class Workspace:
    """Safety box of the tool point in robot coordinates (mm) and its reach radius."""

    x_mm: tuple[float, float]
    y_mm: tuple[float, float]
    z_mm: tuple[float, float]
    reach_mm: float


@dataclass(frozen=True)
class Speeds:
    max_linear_mm_min: float
    max_joint_deg_s: float
    max_accel_mm_s2: float
    attitude_deg_s: float
    # the speed of a move that gives none (``Arm.move``, ``armctl move``/``home``): a value
    # the profile defines, so sending it keeps the rule "never send a value nobody wrote"
    default_linear_mm_min: float = 3000.0
    default_joint_deg_s: float = 30.0


@dataclass(frozen=True)
class Pwm:
    range_us: tuple[float, float]
    channels: tuple[int, ...]
    gripper_open_us: float
    gripper_close_us: float
    initial_us: float


@dataclass(frozen=True)
class Timing:
    joint_ramp_s: tuple[float, ...]  # smoothing levels 1…6
    command_overhead_s: float
    pwm_change_s: float
    pose_smoothing: int

    def ramp_s(self, smoothing: int) -> float:
        """Start/stop ramp of a joint move at smoothing level 0…6 (0 = none)."""
        return 0.0 if smoothing <= 0 else self.joint_ramp_s[min(smoothing, 6) - 1]


@dataclass(frozen=True)
class LintOptions:
    end_gripper: str | None = None  # "open" / "closed"
    end_paused: bool | None = None


# [connector] speed_tolerance: 1 (the arm exactly as its speed_factor says) … 4 (as SPEED_FACTOR_RANGE:
# an arm further off has the wrong speed_factor, not a tolerance).
SPEED_TOLERANCE_RANGE = (1.0, 4.0)
CONTROL_FRAMES = ("queued", "arrival")  # H5, or its alternative
STATUS_XYZ_FRAMES = ("worktable", "robot")  # what status kind 0 reports after G54


@dataclass(frozen=True)
class Connector:
    """The arm's connector and status as they are, where the document leaves them open.

    ``fifo_frames``: frames the connector accepts behind the frame the arm is executing.  The
    document says 200; H6's two readings (the executing frame keeps its slot, or frees it) differ
    only in this sum, the one number a host can observe, so it is one setting.
    ``control_frames``: ``"queued"`` (H5: control frames wait in the FIFO behind motion) or
    ``"arrival"`` (they act the moment they land).  ``status_xyz_frame``: ``"worktable"`` (status
    kind 0 reports X/Y/Z in the frame G54 set) or ``"robot"``.  ``speed_factor``: the arm's real
    motion time ÷ the model's (``MotionModel`` applies it, once, for every reader).
    ``kinematics_verified``: the profile's links were checked against this arm; while false,
    forward and inverse kinematics never decide what the arm consumed or where it starts.
    ``speed_tolerance`` (≥ 1): how far the arm may stray from ``speed_factor``, either way — the
    streamer's time bound confirms a frame once an arm that many times slower (plus
    ``speed_tolerance − 1`` × 20 ms of handling) has finished it, and a sign of loss needs the arm
    that many times faster.  The document pins nothing: 2.0; ``armctl probe`` measures it.
    ``status_jitter_ms``: how much later than its place on the period (first frame + n × 30 ms)
    the arm may build a status frame — the probe's bound on when each frame read was built
    (armctl/probe/stream.py) allows it.  The document gives the period in whole milliseconds: 1."""

    fifo_frames: int
    control_frames: str
    status_xyz_frame: str
    speed_factor: float
    kinematics_verified: bool
    speed_tolerance: float = 2.0
    status_jitter_ms: float = 1.0
    given: frozenset = field(default=frozenset(), compare=False)  # keys a file set (not the document's)

    def is_default(self, key: str) -> bool:
        """Whether ``key`` still has the document's default (no profile, armctl.toml or probe set it)."""
        if key not in CONNECTOR_KEYS:
            raise KeyError(key)
        return key not in self.given

    def fifo_proven(self, port_fifo_frames: int | None = None) -> bool:
        """Whether the connector is known to hold at least ``fifo_frames``: the value was measured
        or set (armctl.toml, a profile file, ``armctl probe --write``), or the port says its own
        FIFO (``port_fifo_frames``: a simulator's option) is at least that.  Otherwise a frame the
        arm dropped looks, to time alone, the same as one it ran."""
        if not self.is_default("fifo_frames"):
            return True
        return port_fifo_frames is not None and port_fifo_frames >= self.fifo_frames

    def control_frames_proven(self, port_control_frames: str | None = None) -> bool:
        """Whether the connector is known to treat control frames as ``control_frames`` says:
        the value was measured or set, or the port says its own (a simulator's option) and it is
        the same.  Otherwise an arm that acts on a POSE or a PROGRAM as it lands (H5) cuts short
        the move before it, and rests at the job's last target all the same."""
        if not self.is_default("control_frames"):
            return True
        return port_control_frames == self.control_frames

    @property
    def control_on_arrival(self) -> bool:
        return self.control_frames == "arrival"

    @property
    def reports_robot_xyz(self) -> bool:
        return self.status_xyz_frame == "robot"


# the [connector] keys, in the order the schema checks them and `armctl config` lists them
CONNECTOR_KEYS = tuple(f.name for f in fields(Connector) if f.name != "given")


@dataclass(frozen=True)
class Profile:
    name: str
    workspace: Workspace
    joint_limits_deg: tuple[tuple[float, float], ...]
    speed: Speeds
    pwm: Pwm
    poses: tuple[tuple[float, ...], ...]  # fixed poses 0…3 as joint angles
    links: Links
    timing: Timing
    lint: LintOptions
    connector: Connector
    source: str = field(default="", compare=False)  # where it was read from, for messages
    # "section.key" → ILLUSTRATIVE, PROTOCOL, PROBE or the file that gave it; see source_of
    sources: dict[str, str] = field(default_factory=dict, compare=False, repr=False)

    def source_of(self, key: str) -> str:
        """Where the number at ``key`` ("section.key") came from; a key without a recorded
        source (a profile built in code) counts as given by its builder."""
        return self.sources.get(key, "given")

    def illustrative(self, keys) -> list[str]:
        """Those of ``keys`` — "section.key", or a whole "section" — whose numbers (any of the
        section's) are the packaged default's illustrative guesses."""
        found = []
        for key in keys:
            if "." in key:
                unmeasured = self.source_of(key) == ILLUSTRATIVE
            else:
                unmeasured = any(k.startswith(key + ".") and v == ILLUSTRATIVE for k, v in self.sources.items())
            if unmeasured:
                found.append(key)
        return found

    @cached_property
    def kinematics(self) -> Kinematics:
        return Kinematics(self.links, self.joint_limits_deg, self.poses[0])
