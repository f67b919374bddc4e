"""Modal state: what the compiler knows between lines, and where it starts from.

Strategy: one flat dict from a *key* to a value, so that a move reads what it omits and writes
what it was given with plain dict operations (this is the compiler's hot path).  Keys:

  X Y Z A B C        the Cartesian target (mm, deg)            — unknown after a joint move
  J1 … J6            the joint target (deg)                    — unknown after a Cartesian move
  U V                external axes E0 E1 (deg), default 0 (the protocol's "unused")
  F_mm_min           Cartesian F, shared by G1, G22x, G300, G301
  F_deg_s            joint F, G6 only (the two families are never mixed)
  K                  acceleration of G22x (mm/s²)
  H                  joint-move smoothing 0…6, default 0 (the protocol's "none")
  T                  the active PWM channel, default 1
  S1 … S4            PWM µs per channel

A value is a float, ``None`` (unknown: nobody wrote it — a move that needs it is an error) or
``POISONED`` (a line tried to set it and failed; the error is already reported, so a later
move that needs it is dropped silently instead of repeating the error).  ``InitialState`` is
the public, typed way to seed the state (from the arm's reported state or a profile), and
``ModalState.snapshot()`` gives one back, e.g. to resume or to chain compilations.
"""

from __future__ import annotations

from dataclasses import field
from typing import Mapping, Optional, Sequence

from ..core.records import record
from .expressions import POISONED  # noqa: F401 - re-exported: the state's "error already reported"

POSE_KEYS = ("X", "Y", "Z", "A", "B", "C")
JOINT_KEYS = ("J1", "J2", "J3", "J4", "J5", "J6")
EXTERNAL_KEYS = ("U", "V")
PWM_KEYS = {channel: f"S{channel}" for channel in (1, 2, 3, 4)}
CARTESIAN_SPEED = "F_mm_min"
JOINT_SPEED = "F_deg_s"

CARTESIAN = "Cartesian target"
JOINTS = "joint target"


# family → the values that make it unknown (applied with dict.update on the hot path)
UNKNOWN = {CARTESIAN: dict.fromkeys(POSE_KEYS), JOINTS: dict.fromkeys(JOINT_KEYS)}


@record
class InitialState:
    """What is known before the first line (default: nothing but the protocol's defaults).

    ``pose`` is X, Y, Z (mm), A, B, C (attitude B0, B1, W in deg) and ``joints_deg`` J1…J6;
    either may be None (unknown) or hold None for an unknown entry.  ``pwm_us`` maps a PWM
    channel (1…4) to its pulse.  ``speed_mm_min`` is the Cartesian F, ``speed_deg_s`` the
    joint F.  ``parameters`` seeds #<name> values (names case-insensitive).
    """

    pose: Optional[Sequence[Optional[float]]] = None
    joints_deg: Optional[Sequence[Optional[float]]] = None
    pwm_us: Mapping[int, float] = field(default_factory=dict)
    pwm_channel: int = 1
    speed_mm_min: Optional[float] = None
    speed_deg_s: Optional[float] = None
    accel_mm_s2: Optional[float] = None
    external_deg: tuple[float, float] = (0.0, 0.0)
    smoothing: int = 0
    relative: bool = False
    parameters: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name, value, size in (("pose", self.pose, 6), ("joints_deg", self.joints_deg, 6)):
            if value is not None and len(value) != size:
                raise ValueError(f"InitialState.{name} needs {size} entries, not {len(value)}")
        if self.pwm_channel not in PWM_KEYS or any(channel not in PWM_KEYS for channel in self.pwm_us):
            raise ValueError("PWM channels are 1…4")


def _number(value) -> Optional[float]:
    return None if value is None else float(value)


class ModalState:
    """The compiler's running knowledge; see the module docstring for the keys."""

    __slots__ = ("values", "relative", "parameters", "unknown_because")

    def __init__(self, initial: InitialState | None = None) -> None:
        initial = initial or InitialState()
        values: dict[str, object] = {}
        values.update(zip(POSE_KEYS, map(_number, initial.pose or (None,) * 6)))
        values.update(zip(JOINT_KEYS, map(_number, initial.joints_deg or (None,) * 6)))
        values.update(zip(EXTERNAL_KEYS, map(float, initial.external_deg)))
        values[CARTESIAN_SPEED] = _number(initial.speed_mm_min)
        values[JOINT_SPEED] = _number(initial.speed_deg_s)
        values["K"] = _number(initial.accel_mm_s2)
        values["H"] = float(initial.smoothing)
        values["T"] = float(initial.pwm_channel)
        for channel, key in PWM_KEYS.items():
            values[key] = _number(initial.pwm_us.get(channel))
        self.values = values
        self.relative = initial.relative
        self.parameters: dict[str, float] = {name.lower(): float(v) for name, v in initial.parameters.items()}
        # why a family of keys is unknown, for hints: family → "G6 on line 12"
        self.unknown_because: dict[str, str] = {}

    def forget(self, family: str, because: str) -> None:
        """Make the Cartesian or the joint target unknown (the host has no kinematics)."""
        self.values.update(UNKNOWN[family])
        self.unknown_because[family] = because

    def snapshot(self) -> InitialState:
        """The known part of this state as an ``InitialState`` (poisoned values count as unknown)."""
        known = {k: (v if type(v) is float else None) for k, v in self.values.items()}
        pose = tuple(known[k] for k in POSE_KEYS)
        joints = tuple(known[k] for k in JOINT_KEYS)
        return InitialState(
            pose=pose if any(v is not None for v in pose) else None,
            joints_deg=joints if any(v is not None for v in joints) else None,
            pwm_us={c: known[k] for c, k in PWM_KEYS.items() if known[k] is not None},
            pwm_channel=int(known["T"] or 1),
            speed_mm_min=known[CARTESIAN_SPEED],
            speed_deg_s=known[JOINT_SPEED],
            accel_mm_s2=known["K"],
            external_deg=(known["U"] or 0.0, known["V"] or 0.0),
            smoothing=int(known["H"] or 0),
            relative=self.relative,
            parameters=dict(self.parameters),
        )
