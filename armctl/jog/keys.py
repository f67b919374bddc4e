"""Raw terminal bytes → key events.

Strategy (sans-I/O, after h11's ``receive_data``/``next_event``): ``KeyDecoder.feed(data, now)``
takes whatever one ``os.read`` returned — a chunk may end in the middle of an escape sequence or
of a UTF-8 character — and returns the keys completed by it; the unfinished tail is kept for the
next chunk.  A lone Esc cannot be told from the start of a sequence until time passes, so it is
held: ``expire(now)`` releases it as ``esc`` once ``escape_s`` has gone by with nothing after it,
and ``deadline()`` says when that is due (the edge loop's ``select`` timeout).  Nothing here
reads a clock or a file descriptor.

Key names are plain strings: a printable character is itself (``"q"``, ``"+"``); the others are
``space``, ``enter``, ``tab``, ``esc``, ``backspace``, ``up``, ``down``, ``left``, ``right``,
``pageup``, ``pagedown``, ``home``, ``end``, ``insert``, ``delete``, ``ctrl-c`` (raw mode turns
Ctrl-C into byte 3, not a signal), ``ctrl-<letter>`` and ``unknown`` (a sequence this table
does not name — still a key, so the caller can treat it as "some other key was pressed").
"""

from __future__ import annotations

import codecs
import re
from dataclasses import dataclass

ESC = 0x1B
ESCAPE_TIMEOUT_S = 0.05  # a lone Esc becomes a key this long after its byte, if nothing follows
MAX_SEQUENCE = 32  # bytes; a longer "sequence" is garbage and is dropped as one unknown key

# Final parts of CSI (ESC [) and SS3 (ESC O) sequences.  Parameters after a ';' are modifiers
# (Shift, Ctrl…), ignored: Ctrl+Up is still Up.
_CSI_LETTERS = {"A": "up", "B": "down", "C": "right", "D": "left", "H": "home", "F": "end"}
_CSI_TILDE = {
    "1": "home", "2": "insert", "3": "delete", "4": "end", "5": "pageup", "6": "pagedown", "7": "home", "8": "end",
}
_SS3 = {"A": "up", "B": "down", "C": "right", "D": "left", "H": "home", "F": "end", "M": "enter"}
_CONTROL = {
    0x03: "ctrl-c", 0x09: "tab", 0x0D: "enter", 0x0A: "enter", 0x7F: "backspace", 0x08: "backspace", 0x20: "space",
}
_CSI_FINAL = re.compile(rb"\x1b\[([0-9;?]*)([\x40-\x7e])")


@dataclass(frozen=True)
class Key:
    """One key press: its name and the time its last byte was read."""

    name: str
    at_s: float


def _control_name(byte: int) -> str:
    if byte in _CONTROL:
        return _CONTROL[byte]
    if 1 <= byte <= 26:
        return f"ctrl-{chr(byte + 96)}"
    return "unknown"


class KeyDecoder:
    """Feed it chunks of bytes read from a terminal in raw mode; get ``Key``s back."""

    def __init__(self, escape_s: float = ESCAPE_TIMEOUT_S) -> None:
        self.escape_s = escape_s
        self._pending = bytearray()  # an escape sequence begun but not finished
        self._pending_since: float | None = None
        self._text = codecs.getincrementaldecoder("utf-8")(errors="replace")

    def deadline(self) -> float | None:
        """When a held Esc turns into a key (None: nothing is held)."""
        if not self._pending:
            return None
        return self._pending_since + self.escape_s

    def expire(self, now: float) -> list[Key]:
        """Release a held Esc (or unfinished sequence) whose time is up."""
        deadline = self.deadline()
        if deadline is None or now < deadline:
            return []
        held, self._pending = bytes(self._pending), bytearray()
        self._pending_since = None
        return [Key("esc" if held == b"\x1b" else "unknown", now)]

    def feed(self, data: bytes, now: float) -> list[Key]:
        keys: list[Key] = []
        for byte in data:
            if self._pending:
                self._pending.append(byte)
                keys.extend(self._continue_sequence(now))
            elif byte == ESC:
                self._pending = bytearray([ESC])
                self._pending_since = now
            elif byte < 0x20 or byte in (0x20, 0x7F):
                keys.append(Key(_control_name(byte), now))
            else:
                for char in self._text.decode(bytes([byte])):
                    keys.append(Key("unknown" if char == "\ufffd" else char, now))
        return keys

    def _continue_sequence(self, now: float) -> list[Key]:
        seq = bytes(self._pending)
        if len(seq) == 2:
            if seq[1] in b"[O":
                return []  # CSI or SS3: more to come
            # ESC followed by anything else: the Esc was a key of its own, then the next byte.
            self._pending = bytearray()
            if seq[1] == ESC:
                self._pending = bytearray([ESC])
                self._pending_since = now
                return [Key("esc", now)]
            return [Key("esc", now), *self.feed(seq[1:], now)]
        if seq[1] == ord("O"):
            self._pending = bytearray()
            return [Key(_SS3.get(chr(seq[2]), "unknown"), now)]
        match = _CSI_FINAL.fullmatch(seq)
        if match is not None:
            self._pending = bytearray()
            return [Key(_csi_name(match[1].decode(), chr(match[2][0])), now)]
        if not re.fullmatch(rb"\x1b\[[0-9;?]*", seq) or len(seq) >= MAX_SEQUENCE:
            self._pending = bytearray()  # not a sequence we can finish: one unknown key
            return [Key("unknown", now)]
        return []


def _csi_name(parameters: str, final: str) -> str:
    if final == "~":
        return _CSI_TILDE.get(parameters.split(";")[0], "unknown")
    return _CSI_LETTERS.get(final, "unknown")
