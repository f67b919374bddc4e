"""Every host→arm command, and ``decode_command``: the one inverse of their ``encode``.

Strategy: the motion commands (armctl/core/motion_commands.py) and the control commands
(armctl/core/control_commands.py) gathered, and a 48-byte frame dispatched to its kind by its head,
command byte and sub-command; anything else is a FrameError or the FieldError of the field a
frame carries wrongly.  armctl/core/protocol.py is the façade; armctl/core/status_frames.py imports
``decode_command`` from here (downwards) to find commands in a byte stream.
"""

from __future__ import annotations

from typing import Union

from .control_commands import (
    GoToPose, Joystick, PauseToggle, ResetArm, ResetConnector, RunProgram, SetWorktableOrigin, StructureMode,
)
from ..errors import FrameError
from .frame_fields import CONTROL_HEAD, CONTROL_TAIL, FRAME_SIZE, MOTION_HEAD, MOTION_TAIL
from .motion_commands import AccelLinearMove, ArcEnd, ArcStart, Delay, JointMove, LinearMove, MCode

AnyCommand = Union[
    LinearMove, AccelLinearMove, JointMove, ArcStart, ArcEnd, Delay, MCode, ResetArm, ResetConnector,
    SetWorktableOrigin, RunProgram, PauseToggle, GoToPose, Joystick, StructureMode,
]

MOTION_COMMANDS = (LinearMove, AccelLinearMove, JointMove, ArcStart, ArcEnd, Delay, MCode)
CONTROL_COMMANDS = (
    ResetArm, ResetConnector, SetWorktableOrigin, RunProgram, PauseToggle, GoToPose, Joystick, StructureMode,
)
# the frames whose motion is the arm's own, not the frame's: an SD program, a fixed pose the
# profile only describes, a reset's homing, a joystick's jog — no model says where they pass
OWN_MOTION_COMMANDS = (RunProgram, GoToPose, ResetArm, Joystick)
_CONTROL_BY_CODE = {(c.A1, c.A2): c for c in CONTROL_COMMANDS}


def decode_command(frame: bytes) -> AnyCommand:
    """The command a 48-byte frame carries; raises FrameError or FieldError if it carries none."""
    frame = bytes(frame)
    if len(frame) != FRAME_SIZE:
        raise FrameError(f"a command frame is {FRAME_SIZE} bytes, not {len(frame)}")
    head, tail = frame[0], frame[-1]
    if head == MOTION_HEAD:
        if tail != MOTION_TAIL:
            raise FrameError(f"motion frame ends with 0x{tail:02x}, expected 0x{MOTION_TAIL:02x}")
        return _decode_motion(frame)
    if head == CONTROL_HEAD:
        if tail != CONTROL_TAIL:
            raise FrameError(f"control frame ends with 0x{tail:02x}, expected 0x{CONTROL_TAIL:02x}")
        kind = _CONTROL_BY_CODE.get((frame[1], frame[2]))
        if kind is None:
            raise FrameError(f"unknown control command {frame[1]}/{frame[2]}")
        return kind._from_frame(frame)
    raise FrameError(f"0x{head:02x} is not a frame head (0x{MOTION_HEAD:02x} or 0x{CONTROL_HEAD:02x})")


def _decode_motion(frame: bytes) -> AnyCommand:
    code = chr(frame[1])
    if code == "4":
        if frame[2] not in (0, 1):
            raise FrameError(f"arc sub-command {frame[2]} is neither 0 (G300) nor 1 (G301)")
        return (ArcStart if frame[2] == 0 else ArcEnd)._from_frame(frame)
    for kind in (LinearMove, AccelLinearMove, JointMove, Delay, MCode):
        if kind.CODE == code:
            return kind._from_frame(frame)
    raise FrameError(f"unknown motion command 0x{frame[1]:02x}")
