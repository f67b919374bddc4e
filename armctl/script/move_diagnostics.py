"""A move that did not take the quick paths: everything wrong with its line, reported at its words.

Strategy: ``MoveDiagnostics`` is path 3 of armctl/script/execute.py — a Lark-parsed line (every
word with its columns) whose move failed on the quick paths, run again from the same untouched
state to report all of it at once: unknown and duplicate words (E002, E003), values that do not
evaluate, what the move lacks (E004, ``_unresolved``), and every value outside the protocol's
range (E005, ``_build``: each reported field gets a placeholder every field accepts, so one pass
checks every word).  What the line did set is committed; what it failed to set is ``POISONED``,
so the same mistake is not reported again on every later line.

Contract with the host class: it provides ``state``, ``file``, ``_sequence`` and the reporter
``_report``.
"""

from __future__ import annotations

import math
from dataclasses import MISSING
from typing import Optional

from ..errors import FieldError
from . import messages
from .expressions import POISONED, ExpressionError, Unavailable, evaluate
from .modal import PWM_KEYS
from .nodes import CodeLine
from .statement import Statement
from .statements import PLACEHOLDER, PLACEHOLDERS, PWM_OF_ACTIVE_CHANNEL, MoveSpec, Resolution, blame, resolve

FLOAT32_MAX = 3.4028234663852886e38


class MoveDiagnostics:
    """Reports everything wrong with a move's line (see the module docstring)."""

    def _move_with_diagnostics(self, number: int, text: str, node: CodeLine, spec: MoveSpec, loop: tuple):
        """``_move`` for a line with spans (Lark-parsed): report everything that is wrong."""
        state, code = self.state, spec.code
        written, failed = self._collect_words(number, text, node, spec)
        resolution = resolve(spec, written, state)
        poison = [] if resolution.ok else self._unresolved(number, text, node, spec, resolution, written)
        command, bad_keys = self._build(number, text, node, spec, written, resolution.arguments)
        values = state.values
        values.update(resolution.updates)
        for key in poison + bad_keys:
            values[key] = POISONED
        if spec.forgets:
            state.forget(spec.forgets, (code, number))
        statement = None
        if command is not None and resolution.ok and not failed:
            statement = Statement(command, self.file, number, node.column, node.end_column, text, code, written,
                                  state.relative, loop)
        return self._sequence(code, number, text, (node.column, node.end_column), statement)

    def _build(self, number, text, node: CodeLine, spec: MoveSpec, written: dict, arguments: list):
        """Build the command, reporting every value out of the protocol's range (E005).

        Fields nothing could fill get a placeholder every field accepts, and so does each
        field once reported, so that one pass checks every word of the line.  Returns the
        command (None if anything was substituted) and the modal keys to poison."""
        arguments = list(arguments)
        substituted = set()
        for index, value in enumerate(arguments):
            if value is MISSING:
                arguments[index] = PLACEHOLDERS.get(spec.field_names[index], PLACEHOLDER)
                substituted.add(index)
        spans = dict(zip((letter for letter, _ in node.words), node.spans))
        bad_keys = []
        for _ in arguments:
            try:
                command = spec.make(*arguments)
            except FieldError as error:
                slot, message = blame(spec, error)
                index = spec.index_of[slot.field] if slot else None
                if index is None or index in substituted:  # pragma: no cover - a placeholder is valid
                    self._report("E005", number, text, node.column, node.end_column, message)
                    return None, bad_keys
                value = arguments[index]
                if isinstance(value, float) and not (math.isfinite(value) and abs(value) <= FLOAT32_MAX):
                    message = f"{slot.letter} is too large for a frame: a 32-bit float holds at most ±3.4e38"
                if slot.letter in written and slot.letter in spans:
                    self._report("E005", number, text, *spans[slot.letter], message)
                else:
                    name = slot.letter or slot.key
                    self._report("E005", number, text, node.column, node.end_column, message,
                                 f"{name} is modal: the value from an earlier line applies; write {name} here")
                key = slot.key
                if key == PWM_OF_ACTIVE_CHANNEL:
                    key = PWM_KEYS.get(arguments[spec.index_of["pwm_channel"]])
                if key:
                    bad_keys.append(key)
                arguments[index] = PLACEHOLDERS.get(slot.field, PLACEHOLDER)
                substituted.add(index)
                continue
            return (None if substituted else command), bad_keys
        return None, bad_keys  # pragma: no cover - each round substitutes one more field

    def _collect_words(self, number, text, node: CodeLine, spec: MoveSpec) -> tuple[dict, bool]:
        """The words' values (letter → number), reporting unknown, duplicate and bad values."""
        written, seen, failed = {}, set(), False
        for (letter, value), (column, end) in zip(node.words, node.spans):
            if letter in seen:
                failed = True
                written.pop(letter, None)
                self._poison_word(spec, letter)
                self._report("E003", number, text, column, end, f"{letter} appears twice in {spec.code}",
                             "a word may appear once per line")
            elif letter not in spec.letter_set:
                failed = True
                self._report("E002", number, text, column, end, *messages.unknown_word(letter, text[column - 1:end - 1], spec))
            else:
                try:
                    written[letter] = evaluate(value, self.state.parameters)
                except ExpressionError as error:
                    failed = True
                    self._poison_word(spec, letter)
                    self._report(error.code, number, text, error.column, error.end_column, error.message, error.hint)
                except Unavailable:
                    failed = True
                    self._poison_word(spec, letter)
            seen.add(letter)
        return written, failed

    def _poison_word(self, spec: MoveSpec, letter: str) -> None:
        key = self._key(spec.key_of.get(letter))
        if key is not None:
            self.state.values[key] = POISONED

    def _key(self, key: Optional[str]) -> Optional[str]:
        if key == PWM_OF_ACTIVE_CHANNEL:
            channel = self.state.values["T"]
            return PWM_KEYS.get(channel) if type(channel) is float else None
        return key

    def _unresolved(self, number, text, node: CodeLine, spec: MoveSpec, resolution: Resolution, written: dict) -> list:
        """Report what a move lacks; return the modal keys to poison."""
        code, head = spec.code, (node.column, node.end_column)
        spans = dict(zip((letter for letter, _ in node.words), node.spans))
        poison = []
        if resolution.bad_channel:
            column, end = spans["T"]
            self._report("E005", number, text, column, end, f"{text[column - 1:end - 1]} is not a PWM channel (1…4)",
                         "T selects the PWM channel of G1; channel 1 drives the tool")
            poison.append("T")
        if resolution.missing:
            letters = [letter for letter, _ in resolution.missing]
            self._report("E004", number, text, *head, messages.missing(code, letters),
                         messages.missing_hint(code, letters, self.state, written.get("T")))
            poison += [key for _, key in resolution.missing]
        # A required word that is on the line but failed (E003, E007, E009) was reported already.
        required = [slot for slot in resolution.required if slot.letter not in spans]
        if required:
            self._report("E004", number, text, *head, *messages.required(code, required))
        for letter, key in resolution.relative_unknown:
            self._report("E004", number, text, *spans[letter],
                         f"{letter} is relative (G91), but no earlier move set {letter}",
                         f"set {letter} with an absolute move (G90) first")
            poison.append(key)
        return poison
