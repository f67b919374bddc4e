"""StatusReader's aligned-burst path (a clean line's bursts: whole valid frames, nothing else)
finds what its byte-by-byte scan finds — the same frames, the same counts — and hands anything
else (a damaged frame, a value no frame carries, a torn tail) to the scan untouched."""

from __future__ import annotations

from dataclasses import fields

from hypothesis import given, settings, strategies as st

from armctl.errors import FieldError, FrameError
from armctl.core.protocol import STATUS_KINDS, StatusReader, decode_status

frame_shaped = st.tuples(st.binary(min_size=6, max_size=6), st.sampled_from(sorted(STATUS_KINDS)) | st.integers(0, 255),
                         st.sampled_from([0xCF, 0xCF, 0xCF, 0x00]), st.sampled_from([0xCE, 0xCE, 0xCE, 0x01])).map(
    lambda t: bytes([t[3]]) + t[0] + bytes([t[1], t[2]]))


def _read(chunks) -> tuple:
    reader = StatusReader()
    found = [frame for chunk in chunks for frame in reader.feed(chunk)]
    return found, reader.frames, reader.skipped_bytes, reader.pending


@settings(max_examples=300, deadline=None)
@given(frames=st.lists(frame_shaped, min_size=1, max_size=6), split=st.booleans())
def test_whole_frame_bursts_read_as_the_scan_reads_them(frames, split):
    data = b"".join(frames)
    chunks = frames if split else [data]
    assert _read(chunks) == _read([data[k:k + 1] for k in range(len(data))])


def test_a_clean_burst_takes_the_aligned_path_and_noise_does_not():
    frame = bytes.fromhex("ce00001194000005cf")
    assert StatusReader._aligned(frame * 3) is not None
    assert StatusReader._aligned(frame[:-1] + b"\x00") is None
    assert StatusReader._aligned(b"\x00" + frame) is None



@settings(max_examples=300, deadline=None)
@given(frame=frame_shaped)
def test_a_frame_read_equals_the_frame_its_checked_constructor_builds(frame):
    """Frames are read past their constructors' checks: the values must be what they give."""
    try:
        read = decode_status(frame)
    except (FrameError, FieldError):
        return
    values = [getattr(read, f.name) for f in fields(read)]
    checked = type(read)(*values)
    assert read == checked
    assert [type(v) for v in values] == [type(getattr(checked, f.name)) for f in fields(read)]
