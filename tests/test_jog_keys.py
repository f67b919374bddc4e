"""Raw terminal bytes → key names (armctl/jog/keys.py).

One table of (bytes, keys) drives every case; each vector is fed whole, byte by byte and split
at every position (an escape sequence may be split across reads), and must give the same keys.
"""

from __future__ import annotations

import pytest
from hypothesis import given, strategies as st

from armctl.jog.keys import ESCAPE_TIMEOUT_S, KeyDecoder

VECTORS = [
    (b"q", ["q"]),
    (b"qaws", ["q", "a", "w", "s"]),
    (b"+-=", ["+", "-", "="]),
    (b" ", ["space"]),
    (b"\r", ["enter"]),
    (b"\n", ["enter"]),
    (b"\t", ["tab"]),
    (b"\x03", ["ctrl-c"]),
    (b"\x04", ["ctrl-d"]),
    (b"\x7f", ["backspace"]),
    (b"\x1b[A\x1b[B\x1b[C\x1b[D", ["up", "down", "right", "left"]),
    (b"\x1bOA\x1bOB\x1bOC\x1bOD", ["up", "down", "right", "left"]),  # application cursor mode
    (b"\x1b[5~\x1b[6~", ["pageup", "pagedown"]),
    (b"\x1b[1;5A", ["up"]),  # Ctrl+Up: modifiers ignored
    (b"\x1b[5;2~", ["pageup"]),
    (b"\x1b[H\x1b[F\x1b[2~\x1b[3~", ["home", "end", "insert", "delete"]),
    (b"\x1b[Z", ["unknown"]),  # Shift-Tab: a key, just not one jog names
    (b"\x1b[200~", ["unknown"]),
    (b"\x1bq", ["esc", "q"]),  # Esc typed right before q (or Alt-q): Esc, then q
    (b"\x1b\x1b[A", ["esc", "up"]),
    (b"q\x1b[Aq", ["q", "up", "q"]),
    ("é".encode(), ["é"]),
    (b"\xff", ["unknown"]),
]


def _feed_in_pieces(pieces: list[bytes]) -> list[str]:
    decoder = KeyDecoder()
    keys = []
    for piece in pieces:
        keys += [k.name for k in decoder.feed(piece, 0.0)]
    keys += [k.name for k in decoder.expire(1.0)]
    return keys


@pytest.mark.parametrize("data, names", VECTORS, ids=[repr(v[0]) for v in VECTORS])
def test_vector_whole_byte_by_byte_and_split(data, names):
    assert _feed_in_pieces([data]) == names
    assert _feed_in_pieces([data[k : k + 1] for k in range(len(data))]) == names
    for cut in range(1, len(data)):
        assert _feed_in_pieces([data[:cut], data[cut:]]) == names, cut


def test_lone_escape_is_esc_only_after_the_timeout():
    decoder = KeyDecoder()
    assert decoder.feed(b"\x1b", 10.0) == []
    assert decoder.deadline() == pytest.approx(10.0 + ESCAPE_TIMEOUT_S)
    assert decoder.expire(10.0 + ESCAPE_TIMEOUT_S / 2) == []
    keys = decoder.expire(10.0 + ESCAPE_TIMEOUT_S)
    assert [k.name for k in keys] == ["esc"]
    assert decoder.deadline() is None


def test_sequence_split_across_reads_within_the_timeout_is_one_key():
    decoder = KeyDecoder()
    assert decoder.feed(b"\x1b", 0.0) == []
    assert decoder.feed(b"[", 0.01) == []
    assert [k.name for k in decoder.feed(b"6~", 0.02)] == ["pagedown"]
    assert decoder.deadline() is None


def test_unfinished_sequence_expires_as_one_unknown_key():
    decoder = KeyDecoder()
    decoder.feed(b"\x1b[5", 0.0)
    assert [k.name for k in decoder.expire(1.0)] == ["unknown"]


def test_endless_sequence_is_dropped_as_unknown():
    keys = _feed_in_pieces([b"\x1b[" + b"1;" * 40 + b"q"])
    assert keys[0] == "unknown" and "q" not in keys[:1]


def test_key_time_is_the_read_time():
    decoder = KeyDecoder()
    assert [(k.name, k.at_s) for k in decoder.feed(b"q", 3.5)] == [("q", 3.5)]


@given(st.lists(st.binary(max_size=12), max_size=12))
def test_any_bytes_give_keys_and_never_raise(pieces):
    decoder = KeyDecoder()
    for piece in pieces:
        for key in decoder.feed(piece, 0.0):
            assert isinstance(key.name, str) and key.name
    decoder.expire(1.0)
    assert decoder.deadline() is None
