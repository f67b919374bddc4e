"""Finding frames in byte streams: StatusReader (fed in chunks) and scan_frames (one buffer).

Strategy (after h11's tests/test_io.py): every golden status vector is fed whole, byte by
byte, split at every position and after junk — including junk made of 0xCE/0xCF and of
almost-frames — and the reader must return exactly that frame and count exactly the junk in
``skipped_bytes``.  Hypothesis then feeds noise in arbitrary chunkings: nothing raises, only
valid frames come out, and what comes out does not depend on the chunking.
"""

from __future__ import annotations

import struct

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from armctl.errors import FieldError, FrameError
from armctl.core.protocol import (
    STATUS_KINDS,
    Chunk,
    Delay,
    PauseToggle,
    PositionStatus,
    ResetArm,
    RunProgram,
    StatusFrame,
    StatusReader,
    decode_command,
    decode_status,
    scan_frames,
)

FAST = settings(max_examples=150, deadline=None)

# Bytes that belong to no frame.  Each may contain status heads and tails, but none of them
# may combine with the bytes of a golden frame that follows into something frame-shaped.
JUNK = {
    "none": "",
    "zero": "00",
    "lone_head": "ce",
    "lone_tail": "cf",
    "heads_and_tails": "ce cf ce cf ce",
    "tail_then_head": "cf ce",
    "unknown_kind_7": "ce 00 00 00 00 00 00 07 cf",
    "unknown_kind_101": "ce 01 02 03 04 05 06 65 cf",
    "wrong_tail": "ce 00 00 00 00 00 00 00 ce",
    "head_only_frame": "ce 00 00 00 00 00 00 00 00",
    "nan_file_length": "ce 00 00 c0 7f 00 00 64 cf",  # framed, but the float is NaN
    "inf_run_position": "ce 00 00 80 7f 00 00 67 cf",  # framed, but the float is +inf
    "truncated_frame": "ce 03 e8 ff ff 80 00 00",  # the first 8 bytes of a position frame
    "command_heads": "ee ef fc fd",
    "every_byte": bytes(range(256)).hex(),
}
JUNK = {name: bytes.fromhex(text) for name, text in JUNK.items()}


def feed_all(chunks) -> tuple[list[StatusFrame], StatusReader]:
    reader = StatusReader()
    found = []
    for chunk in chunks:
        found += reader.feed(chunk)
    return found, reader


def split_at(data: bytes, cuts) -> list[bytes]:
    cuts = [0, *sorted(cuts), len(data)]
    return [data[a:b] for a, b in zip(cuts, cuts[1:])]


# --- each golden status vector, whole, byte by byte, split, after junk --------------------------


@pytest.mark.parametrize("junk", JUNK.values(), ids=JUNK.keys())
def test_status_after_junk_fed_whole(status_vector, junk):
    found, reader = feed_all([junk + status_vector.data])
    assert found == [status_vector.obj]
    assert (reader.skipped_bytes, reader.pending, reader.frames) == (len(junk), 0, 1)


@pytest.mark.parametrize("junk", JUNK.values(), ids=JUNK.keys())
def test_status_after_junk_fed_byte_by_byte(status_vector, junk):
    stream = junk + status_vector.data
    found, reader = feed_all(stream[i : i + 1] for i in range(len(stream)))
    assert found == [status_vector.obj]
    assert (reader.skipped_bytes, reader.pending, reader.frames) == (len(junk), 0, 1)


@pytest.mark.parametrize("junk", [j for j in JUNK.values() if len(j) < 20], ids=[k for k, j in JUNK.items() if len(j) < 20])
def test_status_after_junk_split_at_every_position(status_vector, junk):
    stream = junk + status_vector.data
    for cut in range(len(stream) + 1):
        found, reader = feed_all([stream[:cut], stream[cut:]])
        assert found == [status_vector.obj], f"split at {cut}"
        assert reader.skipped_bytes == len(junk), f"split at {cut}"
        assert reader.pending == 0


def test_status_frame_is_returned_by_the_feed_that_completes_it(status_vector):
    reader = StatusReader()
    for i in range(8):
        assert reader.feed(status_vector.data[i : i + 1]) == []
    assert reader.pending == 8
    assert reader.feed(status_vector.data[8:]) == [status_vector.obj]
    assert reader.feed(b"") == []


@pytest.mark.parametrize("junk", JUNK.values(), ids=JUNK.keys())
def test_junk_after_a_frame_is_counted_once_the_stream_moves_on(all_status_vectors, junk):
    first, second = all_status_vectors[0], all_status_vectors[1]
    reader = StatusReader()
    assert reader.feed(first.data + junk) == [first.obj]
    # junk that may still begin a frame is held back, not yet counted
    assert reader.skipped_bytes + reader.pending == len(junk)
    assert reader.feed(second.data) == [second.obj]
    assert (reader.skipped_bytes, reader.pending, reader.frames) == (len(junk), 0, 2)


def test_whole_status_rotation_with_junk_between(all_status_vectors):
    junks = list(JUNK.values())
    stream, expected_skipped = b"", 0
    for i, vector in enumerate(all_status_vectors):
        junk = junks[i % len(junks)]
        stream += junk + vector.data
        expected_skipped += len(junk)
    for chunks in ([stream], [stream[i : i + 1] for i in range(len(stream))], split_at(stream, range(0, len(stream), 7))):
        found, reader = feed_all(chunks)
        assert found == [v.obj for v in all_status_vectors]
        assert (reader.skipped_bytes, reader.frames, reader.pending) == (expected_skipped, 9, 0)


def test_back_to_back_frames_skip_nothing(all_status_vectors):
    stream = b"".join(v.data for v in all_status_vectors) * 3
    found, reader = feed_all([stream])
    assert found == [v.obj for v in all_status_vectors] * 3
    assert reader.skipped_bytes == 0


def test_unused_status_bytes_are_ignored():
    # kind 4: d0, d2, d3 unused; kind 102: d2..d5 unused
    found, reader = feed_all([bytes.fromhex("ce ff 01 ff ff 05 dc 04 cf  ce 01 02 ff ff ff ff 66 cf")])
    assert [f.fields() for f in found] == [{"pause_state": 1, "pwm_us": 1500}, {"raw": 258}]
    assert reader.skipped_bytes == 0


# --- scan_frames: commands and status mixed with junk -----------------------------------------


def test_scan_frames_literal_offsets():
    position = bytes.fromhex("ce 03 e8 ff ff 80 00 00 cf")
    stream = b"\x01\x02" + ResetArm().encode() + position + b"\xce" + PauseToggle().encode() + b"\xcf"
    assert list(scan_frames(stream)) == [
        Chunk(0, b"\x01\x02"),
        Chunk(2, ResetArm().encode(), ResetArm()),
        Chunk(50, position, PositionStatus(100.0, -0.1, -3276.8)),
        Chunk(59, b"\xce"),
        Chunk(60, PauseToggle().encode(), PauseToggle()),
        Chunk(108, b"\xcf"),
    ]


def test_scan_frames_finds_every_golden_vector_between_junk(all_command_vectors, all_status_vectors):
    vectors = [v for pair in zip(all_command_vectors, all_status_vectors * 3) for v in pair]
    junks = [j for j in JUNK.values() if j]  # never empty, so each frame has junk before it
    stream, expected = b"", []
    # decode names a well-framed status whose float is NaN or inf as an invalid frame (with
    # the reason) rather than as bytes in no frame; the reader above treats it as noise
    invalid = {JUNK["nan_file_length"]: "SD file length carries nan", JUNK["inf_run_position"]: "SD run position carries inf"}
    for i, vector in enumerate(vectors):
        junk = junks[i % len(junks)]
        expected.append(Chunk(len(stream), junk))
        stream += junk
        expected.append(Chunk(len(stream), vector.data, vector.obj))
        stream += vector.data
    chunks = list(scan_frames(stream))
    assert [(c.offset, c.data) for c in chunks] == [(c.offset, c.data) for c in expected]
    for chunk, wanted in zip(chunks, expected):
        if chunk.data in invalid:
            assert chunk.frame is None and chunk.error.startswith(invalid[chunk.data])
        else:
            assert chunk == wanted


def test_scan_frames_back_to_back_commands(all_command_vectors):
    stream = b"".join(v.data for v in all_command_vectors)
    chunks = list(scan_frames(stream))
    assert [c.offset for c in chunks] == [48 * i for i in range(len(all_command_vectors))]
    assert [c.frame for c in chunks] == [v.obj for v in all_command_vectors]


def test_scan_frames_marks_a_framed_command_with_an_impossible_field():
    bad = bytearray(RunProgram(program=15).encode())
    bad[3] = 16
    stream = b"\x00" + bytes(bad) + Delay(delay_ms=250).encode()
    chunks = list(scan_frames(stream))
    assert [(c.offset, len(c.data), c.frame) for c in chunks] == [(0, 1, None), (1, 48, None), (49, 48, Delay(250))]
    assert chunks[1].data == bytes(bad)
    assert "RunProgram.program = 16" in chunks[1].error
    assert chunks[0].error is None and chunks[2].error is None


def test_scan_frames_treats_an_unknown_command_code_as_junk():
    unknown = bytearray(Delay(delay_ms=250).encode())
    unknown[1] = ord("5")  # there is no command '5'
    stream = b"\xcf" + bytes(unknown) + ResetArm().encode()
    assert list(scan_frames(stream)) == [Chunk(0, b"\xcf" + bytes(unknown)), Chunk(49, ResetArm().encode(), ResetArm())]


def test_scan_frames_truncated_frames_are_junk():
    stream = ResetArm().encode()[:47] + bytes.fromhex("ce 03 e8 ff ff 80 00 00")
    assert list(scan_frames(stream)) == [Chunk(0, stream)]


def test_scan_frames_of_nothing():
    assert list(scan_frames(b"")) == []


# --- decode_status errors ---------------------------------------------------------------------


def test_status_reader_and_decode_status_agree_on_what_is_a_frame():
    assert set(STATUS_KINDS) == {0, 1, 2, 3, 4, 5, 100, 102, 103}
    for kind in range(256):
        frame = b"\xce" + bytes(6) + bytes([kind]) + b"\xcf"
        found, reader = feed_all([frame])
        if kind in STATUS_KINDS:
            assert found == [decode_status(frame)]
        else:
            assert found == [] and reader.skipped_bytes + reader.pending == 9  # kind 0xce may begin a frame
            with pytest.raises(FrameError):
                decode_status(frame)


# --- Hypothesis: noise never raises ------------------------------------------------------------

_kind = st.sampled_from(sorted(STATUS_KINDS)) | st.integers(0, 255)
# frame-shaped bytes: a head, 6 arbitrary data bytes (maybe a NaN float), a kind, a tail
status_shaped = st.tuples(st.binary(min_size=6, max_size=6), _kind).map(lambda t: b"\xce" + t[0] + bytes([t[1]]) + b"\xcf")
command_shaped = (
    st.tuples(st.sampled_from([12, 20, 30]), st.integers(0, 10), st.integers(0, 16)).map(
        lambda t: bytes([0xFC, *t]) + bytes(43) + b"\xfd"
    )
    | st.floats(0, 1e6, width=32).map(lambda ms: b"\xee6\x00" + struct.pack("<f", ms) + bytes(40) + b"\xef")
)
noisy_piece = (
    st.binary(max_size=12)
    | st.sampled_from([b"\xce", b"\xcf", b"\xee", b"\xef", b"\xfc", b"\xfd", b"\xce\xcf"])
    | status_shaped
    | command_shaped
    | status_shaped.map(lambda frame: frame[: len(frame) // 2])  # a torn frame
)
noisy_stream = st.lists(noisy_piece, max_size=16).map(b"".join)


@st.composite
def chunked(draw, stream_strategy=noisy_stream):
    data = draw(stream_strategy)
    cuts = draw(st.lists(st.integers(0, len(data)), max_size=12))
    return data, split_at(data, cuts)


@FAST
@given(case=chunked())
def test_noise_never_raises_and_chunking_does_not_matter(case):
    data, chunks = case
    whole, whole_reader = feed_all([data])
    pieces, pieces_reader = feed_all(chunks)
    single, single_reader = feed_all(data[i : i + 1] for i in range(len(data)))
    assert pieces == whole and single == whole
    for reader in (whole_reader, pieces_reader, single_reader):
        assert (reader.skipped_bytes, reader.pending, reader.frames) == (
            whole_reader.skipped_bytes, whole_reader.pending, len(whole),
        )
        # every byte is in a frame, skipped, or held back waiting for more
        assert reader.skipped_bytes + reader.pending + 9 * reader.frames == len(data)
    for frame in whole:
        assert type(frame) in STATUS_KINDS.values()
        assert decode_status(frame.encode()) == frame


def _decodes(frame: bytes) -> bool:
    try:
        decode_status(frame)
    except (FrameError, FieldError):
        return False
    return True


# valid frames with arbitrary data bytes (which may hold 0xCE, 0xCF or unused garbage)
valid_status = st.tuples(st.binary(min_size=6, max_size=6), st.sampled_from(sorted(STATUS_KINDS))).map(
    lambda t: b"\xce" + t[0] + bytes([t[1]]) + b"\xcf"
).filter(_decodes)


@FAST
@given(
    pieces=st.lists(st.tuples(st.binary(max_size=20).map(lambda junk: junk.replace(b"\xce", b"")), valid_status), max_size=8),
    tail=st.binary(max_size=20).map(lambda junk: junk.replace(b"\xce", b"")),
)
def test_frames_between_junk_without_status_heads_are_all_found(pieces, tail):
    """Junk without 0xCE cannot start a frame: every frame is found, exactly the junk skipped."""
    stream = b"".join(junk + frame for junk, frame in pieces) + tail
    found, reader = feed_all([stream])
    assert found == [decode_status(frame) for _, frame in pieces]
    assert reader.skipped_bytes == sum(len(junk) for junk, _ in pieces) + len(tail)
    assert reader.pending == 0


@FAST
@given(data=st.binary(max_size=200) | noisy_stream)
@example(data=b"\xce\x00\x00\x80\x7f\x00\x00d\xcf")  # an SD file length of inf: a 9-byte error chunk
def test_scan_frames_tiles_any_input(data):
    chunks = list(scan_frames(data))
    assert b"".join(c.data for c in chunks) == data
    offset = 0
    for previous, chunk in zip([None, *chunks], chunks):
        assert chunk.offset == offset and chunk.data
        offset += len(chunk.data)
        if chunk.frame is None and chunk.error is None:
            assert previous is None or previous.frame is not None or previous.error is not None, "junk not merged"
        elif chunk.error is not None:  # a well-framed command or status frame with an impossible value
            assert chunk.frame is None and len(chunk.data) in (48, 9)
            with pytest.raises(FieldError):
                (decode_command if len(chunk.data) == 48 else decode_status)(chunk.data)
        elif isinstance(chunk.frame, StatusFrame):
            assert len(chunk.data) == 9 and decode_status(chunk.data) == chunk.frame
        else:
            assert len(chunk.data) == 48 and decode_command(chunk.data) == chunk.frame


@FAST
@given(data=noisy_stream.map(lambda s: s.replace(b"\xee", b"").replace(b"\xfc", b"")))
def test_scan_frames_and_status_reader_find_the_same_status_frames(data):
    """Without command heads in the stream, both find status frames by the same rule (H9)."""
    found, _ = feed_all([data])
    assert [c.frame for c in scan_frames(data) if c.frame is not None] == found
