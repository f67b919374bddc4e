"""What each G code means: which words it takes and how they fill a protocol command.

Strategy: one table (``CODES``) of ``MoveSpec`` — for every G code with words, the protocol
constructor it builds and one ``Slot`` per constructor field: the letter that writes it, the
modal key (armctl/script/modal.py) it falls back to when omitted and updates when written
(``None``: the word is required on every line), and whether G91 makes it relative.  A single
function, ``resolve()``, applies the table to the words of one line and the modal state and
returns a ``Resolution``: the constructor's arguments and the state updates, or what is
missing.  It never mutates the state and never builds the command — the compiler does both,
so a failed line can be re-examined (e.g. re-parsed with columns) without side effects.
``resolve_plain()`` is its lean twin for the compiler's hot path: it answers only when nothing
is wrong, and then exactly as ``resolve()`` does (tests/test_script_fastpath.py).

The protocol constructors stay the one judge of ranges: a ``FieldError`` they raise is turned
into a located diagnostic by the compiler, with ``blame()`` naming the word to blame.
"""

from __future__ import annotations

import re
from dataclasses import MISSING, field
from dataclasses import fields as dataclass_fields
from typing import Callable, NamedTuple, Optional

from ..errors import FieldError
from ..core.protocol import (
    PWM_CHANNELS, AccelLinearMove, ArcEnd, ArcStart, Command, Delay, JointMove, LinearMove, SetWorktableOrigin, f32_repr,
)
from ..core.records import record
from .modal import (
    CARTESIAN, CARTESIAN_SPEED, JOINT_KEYS, JOINT_SPEED, JOINTS, POISONED, POSE_KEYS, PWM_KEYS, ModalState,
)

# The key of "S" in G1 depends on the line's PWM channel T.
PWM_OF_ACTIVE_CHANNEL = "S@T"
_CHANNEL, _PWM_OF_CHANNEL = 1, 2  # resolve()'s special slots


def _special(slot) -> int:
    if slot.letter == "T":
        return _CHANNEL
    return _PWM_OF_CHANNEL if slot.key == PWM_OF_ACTIVE_CHANNEL else 0


@record(slots=True)
class Slot:
    """One constructor field: written by ``letter`` (None: only read from the state), falling
    back to modal ``key`` (None: required on every line), offset from it under G91 if
    ``relative``."""

    field: str
    letter: Optional[str]
    key: Optional[str]
    relative: bool = False
    meaning: str = ""


@record
class MoveSpec:
    code: str
    build: Callable[..., Command]
    slots: tuple[Slot, ...]
    constants: dict = field(default_factory=dict)
    forgets: Optional[str] = None  # the family this statement leaves unknown
    hints: dict = field(default_factory=dict)  # letter → hint when that word is not taken here
    # A rule the language adds over the frame's own ranges: raises FieldError like the build.
    validate: Optional[Callable[[Command], None]] = None
    letters: tuple[str, ...] = field(init=False)  # the words it takes, in table order
    letter_set: frozenset = field(init=False)
    key_of: dict = field(init=False)  # letter → modal key
    index_of: dict = field(init=False)  # constructor field → its position
    field_names: tuple = field(init=False)  # the constructor's fields in order
    defaults: tuple = field(init=False)  # positional arguments before any slot is filled
    plan: tuple = field(init=False)  # the slots as plain tuples, for resolve()'s loop
    is_arc: bool = field(init=False)  # G300/G301: the compiler pairs them
    plain_plan: tuple = field(init=False)  # (index, letter, key) of the ordinary modal slots
    channel_slots: Optional[tuple] = field(init=False)  # (T index, S index) for G1, else None
    construct: Callable[..., Command] = field(init=False)  # build, from every field positionally

    def make(self, *arguments) -> Command:
        """The command from positional constructor arguments; FieldError if a value is wrong."""
        command = self.construct(*arguments)
        if self.validate is not None:
            self.validate(command)
        return command

    def __post_init__(self) -> None:
        letters = tuple(s.letter for s in self.slots if s.letter)
        names = [f.name for f in dataclass_fields(self.build)]
        index_of = {name: index for index, name in enumerate(names)}
        # Positional arguments are faster than keywords; a field no slot fills gets the
        # protocol's own default (or this spec's constant), exactly as if it were omitted.
        defaults = [self.constants.get(f.name, f.default) for f in dataclass_fields(self.build)]
        filled = {s.field for s in self.slots} | set(self.constants)
        unfilled = [f.name for f in dataclass_fields(self.build) if f.default is MISSING and f.name not in filled]
        assert not unfilled, f"{self.code}: no slot fills {unfilled}"
        set_ = object.__setattr__
        set_(self, "letters", letters)
        set_(self, "letter_set", frozenset(letters))
        set_(self, "key_of", {s.letter: s.key for s in self.slots if s.letter})
        set_(self, "index_of", index_of)
        set_(self, "field_names", tuple(names))
        set_(self, "construct", getattr(self.build, "from_fields", self.build))
        set_(self, "is_arc", self.code in ("G300", "G301"))
        set_(self, "plain_plan", tuple((index_of[s.field], s.letter, s.key) for s in self.slots if not _special(s)))
        special = {_special(s): index_of[s.field] for s in self.slots if _special(s)}
        set_(self, "channel_slots", (special[_CHANNEL], special[_PWM_OF_CHANNEL]) if special else None)
        set_(self, "defaults", tuple(defaults))
        set_(self, "plan", tuple((index_of[s.field], s.letter, s.key, s.relative, _special(s), s) for s in self.slots))


_POSE_FIELDS = ("x_mm", "y_mm", "z_mm", "b0_deg", "b1_deg", "w_deg")
_POSE = tuple(Slot(f, k, k, True) for f, k in zip(_POSE_FIELDS, POSE_KEYS))
_JOINTS = tuple(Slot(f"j{i}_deg", k, k, True) for i, k in enumerate(JOINT_KEYS, 1))
_EXTERNAL = (Slot("e0_deg", "U", "U", True), Slot("e1_deg", "V", "V", True))
_EXTERNAL_KEPT = (Slot("e0_deg", None, "U"), Slot("e1_deg", None, "V"))  # arcs: modal U V, not writable
_PWM_CHANNEL_1 = Slot("pwm_us", "S", "S1")
_CARTESIAN_F = CARTESIAN_SPEED

_NO_PWM = "accelerated moves carry no PWM value; set S with G1 or G6"
_CHANNEL_1_ONLY = "this frame has no PWM channel byte: its S drives channel 1"
_ARC_EXTERNAL = "arcs keep the external axes where the last move put them"


def _rising_ramp(code: str):
    """G222 and G230 ramp up to speed1 (PROTOCOL.md: modes 1 and 2 take a > 0); the frame
    could carry any K, the language refuses what the vendor says those modes do not take."""

    def validate(command: AccelLinearMove) -> None:
        if command.accel_mm_s2 <= 0:
            raise FieldError(f"AccelLinearMove.accel_mm_s2 = {f32_repr(command.accel_mm_s2)} must be greater "
                             f"than 0 in {code} (it ramps up to F; only G220 takes a negative K)")

    return validate


def _accelerated(code: str, mode: int) -> MoveSpec:
    slots = _POSE + _EXTERNAL + (Slot("accel_mm_s2", "K", "K"), Slot("speed1_mm_min", "F", _CARTESIAN_F))
    hints = {"S": _NO_PWM, "T": _NO_PWM}
    if mode == 2:
        slots += (Slot("speed0_mm_min", "Q", None, meaning="speed0, mm/min, the speed the ramp starts from"),)
    else:
        hints["Q"] = "Q (speed0) belongs to G230 only"
    validate = None if mode == 0 else _rising_ramp(code)
    return MoveSpec(code, AccelLinearMove, slots, {"mode": mode}, JOINTS, hints, validate)


CODES: dict[int, MoveSpec] = {
    1: MoveSpec(
        "G1", LinearMove,
        _POSE + (Slot("pwm_channel", "T", "T"), Slot("pwm_us", "S", PWM_OF_ACTIVE_CHANNEL),
                 Slot("speed_mm_min", "F", _CARTESIAN_F)) + _EXTERNAL,
        forgets=JOINTS,
    ),
    220: _accelerated("G220", 0),
    222: _accelerated("G222", 1),
    230: _accelerated("G230", 2),
    6: MoveSpec(
        "G6", JointMove,
        _JOINTS + (_PWM_CHANNEL_1,) + _EXTERNAL + (Slot("smoothing", "H", "H"), Slot("speed_deg_s", "F", JOINT_SPEED)),
        forgets=CARTESIAN, hints={"T": _CHANNEL_1_ONLY},
    ),
    300: MoveSpec(
        "G300", ArcStart,
        _POSE + (_PWM_CHANNEL_1, Slot("radius_mm", "R", None, meaning="the arc radius, mm"),
                 Slot("speed_mm_min", "F", _CARTESIAN_F)) + _EXTERNAL_KEPT,
        forgets=JOINTS, hints={"T": _CHANNEL_1_ONLY, "U": _ARC_EXTERNAL, "V": _ARC_EXTERNAL},
    ),
    301: MoveSpec(
        "G301", ArcEnd,
        _POSE + (_PWM_CHANNEL_1, Slot("speed_mm_min", "F", _CARTESIAN_F)) + _EXTERNAL_KEPT,
        forgets=JOINTS, hints={"T": _CHANNEL_1_ONLY, "U": _ARC_EXTERNAL, "V": _ARC_EXTERNAL,
                               "R": "the radius goes on the G300 line"},
    ),
    4: MoveSpec("G4", Delay, (Slot("delay_ms", "P", None, meaning="the delay, ms"),)),
    54: MoveSpec(
        "G54", SetWorktableOrigin,
        tuple(Slot(f, k, None, meaning="the origin in robot coordinates, mm") for f, k in zip(_POSE_FIELDS[:3], "XYZ")),
        forgets=CARTESIAN,
    ),
}

# Statements without words, handled by the compiler itself.
DISTANCE_MODES = {90: False, 91: True}  # G90 absolute, G91 relative
KNOWN_G_CODES = sorted(CODES.keys() | DISTANCE_MODES.keys())
UNKNOWN_G_HINTS = {
    0: "there is no rapid move: use G1 with F",
    2: "arcs are G300 (through a point, with R) then G301 (the end point)",
    3: "arcs are G300 (through a point, with R) then G301 (the end point)",
    21: "units are always mm",
    28: "use POSE n to go to a fixed pose",
}


class Resolution(NamedTuple):
    """The outcome of applying a ``MoveSpec`` to one line's words and the modal state."""

    ok: bool  # nothing below went wrong: ``arguments`` are complete
    arguments: list  # positional, in the constructor's field order
    updates: dict
    missing: list  # (letter, key) whose modal value nobody set
    required: list  # slots required on every line that the line lacks
    relative_unknown: list  # (letter, key) written under G91 whose base value is unknown
    blocked: bool  # a needed value is POISONED (its error is already reported)
    bad_channel: bool  # T is not a PWM channel (reported by the compiler)


def resolve(spec: MoveSpec, written: dict, state: ModalState) -> Resolution:
    """Fill ``spec``'s fields from ``written`` (letter → number) and ``state``; no side effects.

    ``arguments`` are positional, in the constructor's field order; a field nothing could
    fill is left as ``dataclasses.MISSING``."""
    values = state.values
    relative = state.relative
    arguments = list(spec.defaults)
    updates: dict = {}
    missing: list = []
    required: list = []
    relative_unknown: list = []
    blocked = bad_channel = False
    channel = None
    get = written.get
    for index, letter, key, relative_slot, special, slot in spec.plan:
        if special:
            if special == _PWM_OF_CHANNEL:
                if channel is None:  # T is bad or unavailable: already accounted for
                    continue
                key = PWM_KEYS[channel]
            else:  # T: the channel, checked before any use
                value = get(letter)
                if value is None:
                    value = values[key]
                    if value is POISONED:
                        blocked = True
                        continue
                elif value in PWM_CHANNELS:
                    updates[key] = value
                else:
                    bad_channel = True
                    continue
                arguments[index] = channel = int(value)
                continue
        value = get(letter)
        if value is None:
            if key is None:
                required.append(slot)
                continue
            value = values[key]
            if value.__class__ is not float:
                if value is None:
                    missing.append((letter or key, key))
                else:
                    blocked = True
                continue
        elif key is not None:
            if relative and relative_slot:
                base = values[key]
                if base.__class__ is not float:
                    if base is None:
                        relative_unknown.append((letter, key))
                    else:
                        blocked = True
                    continue
                value = base + value
            updates[key] = value
        arguments[index] = value
    ok = not (missing or required or relative_unknown or blocked or bad_channel)
    return Resolution(ok, arguments, updates, missing, required, relative_unknown, blocked, bad_channel)


class PlainPlan(NamedTuple):
    """How the hot path fills a statement's arguments from one shape of plain line: the words'
    letters in the order written (``plain_plan`` builds it once per shape)."""

    spec: MoveSpec
    letters: tuple  # canonical letters, as written
    write_index: tuple  # the argument each written word fills (S excluded)
    write_keys: tuple  # the modal key each written word sets (S excluded)
    fetch: tuple  # (argument index, modal key) of the slots the line does not write
    pwm: Optional[tuple]  # G1: (T's index, S's index, the position of S among the words or -1)
    # run(words, values) → (command, updates, written) or None: the compiler's hot path for this
    # shape, resolve() and the protocol constructor as straight-line code (see _plan_functions);
    # ``words`` alternates the letters and the numbers as written (strings or floats), ``written``
    # maps letter → number; a value the protocol refuses raises its FieldError.  ``arguments``
    # is the same with the constructor's arguments in place of the command (resolve_planned).
    run: Callable
    arguments: Callable


def plain_plan(spec: MoveSpec, letters: tuple) -> Optional[PlainPlan]:
    """The plan for a line of ``spec`` writing ``letters`` (canonical, as written), or None when
    the general path must judge it (a repeated or foreign letter, a T, a slot without a key)."""
    if len(set(letters)) != len(letters) or not set(letters) <= spec.letter_set or "T" in letters:
        return None
    pwm = spec.channel_slots is not None  # G1: S sets the PWM of the active channel (special slots)
    slot_of = {letter: (index, key) for index, letter, key in spec.plain_plan if letter}
    written = tuple(letter for letter in letters if not (pwm and letter == "S"))
    if any(slot_of[letter][1] is None for letter in written):
        return None
    fetch = tuple((index, key) for index, letter, key in spec.plain_plan if letter not in letters)
    if any(key is None for _, key in fetch):
        return None  # a required word is missing: resolve() says so
    write_index = tuple(slot_of[letter][0] for letter in written)
    write_keys = tuple(slot_of[letter][1] for letter in written)
    pwm_plan = (*spec.channel_slots, letters.index("S") if "S" in letters else -1) if pwm else None
    return PlainPlan(spec, letters, write_index, write_keys, fetch, pwm_plan,
                     *_plan_functions(spec, letters, write_index, write_keys, fetch, pwm_plan))


def _plan_functions(spec: MoveSpec, letters: tuple, write_index: tuple, write_keys: tuple, fetch: tuple,
                    pwm: Optional[tuple]) -> tuple[Callable, Callable]:
    """``run`` and ``arguments`` for one line shape (see ``PlainPlan``) as straight-line Python,
    compiled once per shape (as ``dataclasses`` compiles ``__init__``): a line then costs a
    float() per word, a lookup and a class test per value it takes from the state, one call of
    the protocol constructor with every field positionally (``fields_builder``: no argument
    list, no per-field setattr) and two dicts — no loop over slots.  They do exactly what
    ``resolve_planned``'s definition says, then ``spec.make``; tests/test_script_fastpath.py
    holds both to ``resolve()`` and ``spec.make`` on generated states."""
    body = [f"    n{k} = float(words[{2 * k + 1}])" for k in range(len(letters))]
    argument = {index: repr(default) if type(default) in (int, float) else f"defaults[{index}]"
                for index, default in enumerate(spec.defaults)}
    numbers = [f"n{k}" for k in range(len(letters))]
    written = [number for k, number in enumerate(numbers) if not (pwm is not None and k == pwm[2])]
    for index, number in zip(write_index, written):
        argument[index] = number
    for index, key in fetch:
        body += [f"    v{index} = values[{key!r}]", f"    if v{index}.__class__ is not float:", "        return None"]
        argument[index] = f"v{index}"
    updates = ", ".join(f"{key!r}: {number}" for key, number in zip(write_keys, written))
    body.append(f"    updates = {{{updates}}}")
    if pwm is not None:
        channel_index, pwm_index, s_at = pwm
        body += ["    channel = values['T']", "    if channel.__class__ is not float:", "        return None",
                 "    channel = int(channel)"]
        if s_at < 0:
            body += ["    pwm = values[PWM_KEYS[channel]]", "    if pwm.__class__ is not float:", "        return None"]
        else:
            body += [f"    pwm = updates[PWM_KEYS[channel]] = n{s_at}"]
        argument[channel_index], argument[pwm_index] = "channel", "pwm"
    arguments = ", ".join(argument[index] for index in range(len(spec.defaults)))
    written_dict = ", ".join(f"{letter!r}: {number}" for letter, number in zip(letters, numbers))
    build = getattr(spec.build, "fields_builder", lambda: spec.construct)()
    run = body + [f"    command = build({arguments})"]
    if spec.validate is not None:
        run.append("    validate(command)")
    run.append(f"    return command, updates, {{{written_dict}}}")
    source = "\n".join(["def run(words, values):", *run, "def arguments(words, values):", *body,
                         f"    return ({arguments},), updates, {{{written_dict}}}", ""])
    namespace = {"PWM_KEYS": PWM_KEYS, "defaults": spec.defaults, "build": build, "validate": spec.validate}
    exec(compile(source, f"<plan {spec.code} {' '.join(letters)}>", "exec"), namespace)  # noqa: S102 - our own source
    return namespace["run"], namespace["arguments"]


def resolve_planned(plan: PlainPlan, numbers: list, values: dict) -> Optional[tuple[list, dict]]:
    """``resolve()``'s common case, lean: (arguments, updates) for a line of ``plan``'s shape with
    the words' ``numbers`` as written, when nothing is missing, unknown or poisoned; None
    otherwise (then ``resolve()`` says what is wrong).  The caller must only use it in absolute
    mode (G90).  Arguments: the written words in their slots (S in the active channel's PWM
    slot), every other slot from the modal state (each must hold a float), the channel from T;
    updates: each written word's modal key (S: the active channel's PWM key).  It is
    ``plan.arguments``; the compiler's hot path calls ``plan.run``, the same followed by the
    constructor.  It agrees with ``resolve()`` whenever it answers (tests/test_script_fastpath.py
    checks this on generated states)."""
    words = [item for pair in zip(plan.letters, numbers) for item in pair]
    found = plan.arguments(words, values)
    if found is None:
        return None
    return list(found[0]), found[1]


_FIELD_IN_MESSAGE = re.compile(r"^\w+\.(\w+)")


def blame(spec: MoveSpec, error: Exception) -> tuple[Optional[Slot], str]:
    """For a FieldError from ``spec.build``: the slot to blame (None if the message names no
    field of ours) and the message in the user's words.

    The protocol words its errors as ``Class.field …``; the field becomes the word that
    wrote it (``LinearMove.pwm_us = 3000 is outside 500…2500`` → ``S = 3000 is outside …``).
    """
    text = str(error)
    match = _FIELD_IN_MESSAGE.match(text)
    if match:
        for slot in spec.slots:
            if slot.field == match.group(1):
                return slot, (slot.letter or slot.key or slot.field) + text[match.end():]
    return None, text


# A value every field accepts, to range-check the other fields of a line that has an error.
PLACEHOLDERS = {"pwm_us": 1500.0}
PLACEHOLDER = 1.0
