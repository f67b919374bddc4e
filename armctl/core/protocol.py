"""The arm's serial protocol: every frame as an immutable object ⇄ its exact bytes (the façade).

Strategy (after h11): the protocol knows bytes and nothing else — no port, no clock, no I/O.
Host→arm commands are frozen dataclasses whose fields carry their units in their names
(``x_mm``, ``speed_mm_min``); ``encode()`` gives the 48 bytes and ``decode_command()`` is the
one inverse.  Arm→host status frames likewise, with ``decode_status()`` and a ``StatusReader``
that is fed arbitrary chunks and resynchronises after noise.

Fields are validated and *normalised* on construction: floats are rounded to IEEE single
precision, status values to their wire resolution.  So an object holds exactly what will be
on the wire, and ``decode(encode(x)) == x`` for every valid ``x``.

This module is the one place callers import the protocol from; its parts, each importing
only downwards:

- armctl/core/frame_fields.py — the wire's numbers (heads, tails, codecs, ranges: every hypothesis
  PROTOCOL.md labels H1…H9 that concerns bytes, as one named constant marked with its label),
  the field normalisation (``f32_field``, ``as_f32``, ``f32_repr``) and the ``Command`` base;
- armctl/core/motion_commands.py — the seven 0xEE motion commands;
- armctl/core/control_commands.py — the eight 0xFC control commands;
- armctl/core/commands.py — all fifteen, and ``decode_command``;
- armctl/core/status_frames.py — status frames, finding frames in a byte stream and the readable
  form, and armctl/core/status_reader.py — the resynchronising ``StatusReader``: both imported on
  first use (the module ``__getattr__`` below), so compile and lint never build them.  They
  import the parts above, never this façade.
"""

from __future__ import annotations

from .commands import AnyCommand, CONTROL_COMMANDS, MOTION_COMMANDS, decode_command  # noqa: F401
from .control_commands import (  # noqa: F401
    GoToPose, Joystick, PauseToggle, ResetArm, ResetConnector, RunProgram, SetWorktableOrigin, StructureMode,
)
from .frame_fields import (  # noqa: F401
    ACCEL_RANGE_MM_S2, BITS_PER_BYTE, CONNECTOR_BUFFER_BYTES, CONNECTOR_BUFFER_FRAMES, CONTROL_HEAD, CONTROL_TAIL,
    DEFAULT_BAUD, FIXED_POSE_RANGE, FLOAT_CODEC, FRAME_SIZE, JOYSTICK_JOINT_AXES, JOYSTICK_LINEAR_AXIS,
    JOYSTICK_NEUTRAL, JOYSTICK_STILL_RANGE, LINEAR_SUBCOMMAND_FOR_CHANNEL_1, M_CODE_CODEC, MOTION_HEAD, MOTION_TAIL,
    PAUSE_TOGGLE_ARGUMENT, PROGRAM_RANGE, PWM_CHANNELS, PWM_RANGE_US, SMOOTHING_RANGE, STATUS_HEAD, STATUS_PERIOD_S,
    STATUS_SIZE, STATUS_TAIL, STATUS_WORD_CODEC, STRUCTURE_MODE_ARGUMENT, Command, as_f32, byte_seconds, f32_repr,
    frame_seconds,
)
from .motion_commands import AccelLinearMove, ArcEnd, ArcStart, Delay, JointMove, LinearMove, MCode  # noqa: F401


# --- status frames, byte streams, readable form, the reader: status_frames.py, status_reader.py ---


def __getattr__(name: str):
    """``StatusFrame``, ``decode_status``, ``scan_frames``, ``describe`` … live in
    armctl/core/status_frames.py and ``StatusReader`` in armctl/core/status_reader.py, imported on first
    use (a command that never reads the arm does not build them at every start); they are part
    of this module's interface all the same."""
    if name.startswith("__"):  # the import system asks for __path__ at every "from armctl.core.protocol import …"
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from . import status_frames, status_reader

    for module in (status_frames, status_reader):
        if name in vars(module):
            return vars(module)[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
