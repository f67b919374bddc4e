"""The sentences and hints of the compiler's diagnostics, in one place.

Strategy: the compiler decides *that* something is wrong and where; this module words it.
Messages say what is wrong in the user's terms (words, lines, units), hints say what to do.
Kept apart so that tests can pin the wording and reviewers can read all of it at once.
"""

from __future__ import annotations

from .modal import CARTESIAN, CARTESIAN_SPEED, JOINT_KEYS, JOINT_SPEED, JOINTS, POSE_KEYS, ModalState
from .statements import KNOWN_G_CODES, UNKNOWN_G_HINTS, MoveSpec

ARC_HINT = "an arc is G300 (a point on the arc, with R) directly followed by G301 (its end point)"
STATEMENTS_HINT = (
    "statements are G and M codes (G1 G4 G6 G54 G90 G91 G220 G222 G230 G300 G301, M…), "
    "RESET, RESET CONNECTOR, PAUSE, POSE n, PROGRAM n, MODE 0|1, #<name> = value and O<label> repeat/endrepeat"
)


def not_utf8(char: str) -> str:
    code = ord(char)
    if 0xDC80 <= code <= 0xDCFF:  # a byte that did not decode (surrogateescape)
        return f"byte 0x{code - 0xDC00:02x} is not UTF-8 text"
    return f"character U+{code:04X} is not valid text"


def unknown_g_code(number: int) -> str:
    return UNKNOWN_G_HINTS.get(number) or "known G codes: " + " ".join(f"G{n}" for n in KNOWN_G_CODES)


def unknown_word(letter: str, written: str, spec: MoveSpec) -> tuple[str, str]:
    """(message, hint) for a word ``spec`` does not take."""
    code = spec.code
    if letter == "N":
        return f"line number {written} must start the line", "write N… first, or leave it out"
    if letter in ("G", "M"):
        return (f"one statement per line: {written.upper()} must be on a line of its own",
                f"{code} already starts this line")
    hint = spec.hints.get(letter)
    if hint is None and letter in JOINT_KEYS:
        hint = "joint angles J1=… J6= go with G6"
    elif hint is None and letter in POSE_KEYS and code == "G6":
        hint = "G6 moves joints (J1=… J6=); X Y Z A B C go with G1"
    elif hint is None:
        hint = f"{code} takes " + " ".join(_shown(spec.letters))
    return f"unknown word '{letter}' in {code}", hint


def _shown(letters) -> list[str]:
    return [f"{letter}=" if letter.startswith("J") else letter for letter in letters]


def missing(code: str, letters: list[str]) -> str:
    return f"{code} needs {', '.join(letters)}: no earlier move set {'it' if len(letters) == 1 else 'them'}"


def missing_hint(code: str, letters: list[str], state: ModalState, channel=None) -> str:
    """Why the values are unknown, when the state knows, and what to write."""
    for family, keys in ((CARTESIAN, POSE_KEYS), (JOINTS, JOINT_KEYS)):
        because = state.unknown_because.get(family)
        if because and any(letter in keys for letter in letters):
            what, line = because
            needed = "X Y Z A B C" if family == CARTESIAN else "J1= … J6="
            return (f"{what} on line {line} left the {family} unknown (the host has no kinematics): "
                    f"write all of {needed} on this move")
    if "S" in letters and code == "G1":
        channel = channel if channel is not None else state.values["T"]
        if channel in (2.0, 3.0, 4.0):
            return f"S is kept per PWM channel; channel {int(channel)} has none yet: write S on this line"
    other_speed = state.values[CARTESIAN_SPEED if code == "G6" else JOINT_SPEED]
    if letters == ["F"] and type(other_speed) is float:
        unit = "deg/s" if code == "G6" else "mm/min"
        return f"write F ({unit}) on this line: Cartesian moves (mm/min) and G6 (deg/s) keep separate speeds"
    return f"write {' '.join(_shown(letters))} on this line, or start from a known state"


def required(code: str, slots) -> tuple[str, str]:
    """(message, hint) for words that must be written on every such line."""
    letters = [slot.letter for slot in slots]
    meanings = "; ".join(dict.fromkeys(f"{slot.meaning}" for slot in slots if slot.meaning))
    return (f"{code} needs {', '.join(letters)}",
            f"{' '.join(letters)} must be written on every {code} ({meanings})")
