"""Teach: a reported pose as one line of the motion-script language.

Strategy: pure formatting.  Every taught line carries every word its move needs — ``G1 X Y Z
A B C S F`` in linear mode, ``G6 J1= … J6= S F`` in joint mode — so any line can be the first
of the file, lines can be reordered or deleted, and the file compiles and lints without
relying on modal state (a G6 leaves the Cartesian target unknown to the compiler, and the
other way round).  Values are written at the status resolution (0.1 mm, 0.01 deg) with
trailing zeros dropped; the comment names the local time with its UTC offset.

A taught file always lints clean: what the arm reports outside the language's ranges (a PWM
of 0 from a servo that sends no pulse, say) would make the line an E005 error, so it is
clamped into the range and the line's comment says what was reported and what was written.
"""

from __future__ import annotations

from datetime import datetime

from ..core.protocol import PWM_RANGE_US
from .keymap import JOINT
from .moves import Reported

FILE_HEADER = "; poses taught with armctl jog (G1: linear mode, G6: joint mode); replay with `armctl run FILE`\n"


def number(value: float, digits: int) -> str:
    """``value`` rounded to ``digits`` decimals, without trailing zeros or a negative zero."""
    text = f"{value:.{digits}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def taught_line(mode: str, pose: Reported, speed: float, when: datetime) -> str:
    """The line (with its newline) that replays ``pose``: G6 in joint mode, else G1.

    ``speed`` is F: deg/s for G6, mm/min for G1."""
    if mode == JOINT:
        words = ["G6", *(f"J{k}={number(v, 2)}" for k, v in enumerate(pose.joints_deg, 1))]
    else:
        x, y, z = pose.xyz_mm
        a, b, c = pose.attitude_deg
        words = ["G1", f"X{number(x, 1)}", f"Y{number(y, 1)}", f"Z{number(z, 1)}",
                 f"A{number(a, 2)}", f"B{number(b, 2)}", f"C{number(c, 2)}"]
    pwm, note = _pwm_word(pose.pwm_us)
    words += [pwm, f"F{_speed(speed)}"]
    return f"{' '.join(words)} ; taught {when.isoformat(timespec='seconds')}{note}\n"


def _pwm_word(pwm_us: float) -> tuple[str, str]:
    """(the S word, a note for the comment): a reported PWM outside the protocol's range is
    clamped into it — a line with it would not compile (E005) — and the note says so."""
    low, high = PWM_RANGE_US
    written = number(pwm_us, 0)
    if low <= float(written) <= high:
        return f"S{written}", ""
    clamped = min(max(pwm_us, low), high)
    return f"S{clamped:.0f}", (f"; the arm reported PWM {written} us, outside the language's {low:.0f}-{high:.0f} us:"
                               f" written as S{clamped:.0f}, check the gripper before replaying")


def _speed(speed: float) -> str:
    """F at 0.1 resolution, but never rounded down to 0 (a speed must be positive, E005)."""
    text = number(speed, 1)
    return text if text != "0" else number(max(speed, 1e-6), 6)
