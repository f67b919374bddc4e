"""A motion command's floats are rounded in one pack/unpack (issue 13: cheap construction); any
unusual value takes the field-by-field path.  Both must give the same object or the same error:
a float subclass forces the field-by-field path for the comparison."""

from __future__ import annotations

import math
from dataclasses import fields as dataclass_fields

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.errors import FieldError
from armctl.core.protocol import AccelLinearMove, ArcEnd, ArcStart, Delay, JointMove, LinearMove


class _Slow(float):
    """Not an exact float: construction takes the field-by-field path."""


def _outcome(cls, values: dict):
    try:
        command = cls(**values)
    except FieldError as error:
        return ("error", str(error))
    return ("ok", [(name, getattr(command, name), math.copysign(1.0, getattr(command, name))) for name in cls.SLOTS])


NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True), st.floats(-1e4, 1e4), st.integers(-(2**70), 2**70),
    st.sampled_from([0.0, -0.0, 3.4028234663852886e38, 3.4028235677973366e38, 1e39, 1e-46, 1500, 3000.0]),
)


@settings(max_examples=300, deadline=None)
@given(st.sampled_from([LinearMove, AccelLinearMove, JointMove]), st.data())
def test_the_one_pack_path_gives_what_the_field_by_field_path_gives(cls, data):
    values = {name: data.draw(NUMBERS, label=name) for name in cls.SLOTS}
    if cls is AccelLinearMove:
        values["mode"] = 2
    slow = {name: _Slow(value) if name in cls.SLOTS else value for name, value in values.items()}
    fast_outcome, slow_outcome = _outcome(cls, values), _outcome(cls, slow)
    if fast_outcome[0] == "ok":
        assert slow_outcome[0] == "ok"
        assert all(type(value) is float for _, value, _ in fast_outcome[1])
        assert [(n, v if v == v else "nan", s) for n, v, s in fast_outcome[1]] == \
               [(n, v if v == v else "nan", s) for n, v, s in slow_outcome[1]]
    else:
        assert fast_outcome == slow_outcome


def test_bools_and_strings_are_refused_as_before():
    good = dict(x_mm=1, y_mm=2, z_mm=3, b0_deg=180, b1_deg=0, w_deg=0, pwm_us=1500, speed_mm_min=3000)
    with pytest.raises(FieldError, match="y_mm must be a number, not True"):
        LinearMove(**{**good, "y_mm": True})
    with pytest.raises(FieldError, match="z_mm must be a number, not '3'"):
        LinearMove(**{**good, "z_mm": "3"})
    with pytest.raises(OverflowError):  # as before: float() of an int beyond a double
        LinearMove(**{**good, "x_mm": 10**400})


def _built(build, cls, values: tuple):
    try:
        command = build(*values)
    except FieldError as error:
        return ("error", str(error))
    assert type(command) is cls
    return ("ok", [(name, repr(value)) for name, value in command.__dict__.items()], hash(command))


@settings(max_examples=300, deadline=None)
@given(st.sampled_from([LinearMove, AccelLinearMove, JointMove, ArcStart, ArcEnd, Delay]), st.data())
def test_from_fields_builds_what_the_constructor_builds(cls, data):
    """The compiler's constructor (one dictionary update) against the dataclass's own: the same
    fields, the same float32 values and signs, the same error."""
    names = [f.name for f in dataclass_fields(cls)]
    values = tuple(data.draw(NUMBERS if name in cls.SLOTS else st.sampled_from([0, 1, 2, 3, 4, 5, 7, 1.0, True]),
                             label=name) for name in names)
    assert _built(cls.from_fields, cls, values) == _built(cls, cls, values)


FLOATS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True), st.floats(-1e4, 1e4),
    st.sampled_from([0.0, -0.0, 3.4028234663852886e38, 3.4028235677973366e38, 1e39, -1e39, 1e-46, 1500.0, 3000.0]),
)


@settings(max_examples=300, deadline=None)
@given(st.sampled_from([LinearMove, AccelLinearMove, JointMove, ArcStart, ArcEnd, Delay]), st.data())
def test_from_fields_with_every_float_field_a_float(cls, data):
    """What the compiler passes (every float field a float): from_fields' compiled straight-line
    path against the dataclass's own constructor, rounding, overflow, inf and NaN included."""
    names = [f.name for f in dataclass_fields(cls)]
    values = tuple(data.draw(FLOATS if name in cls.SLOTS else st.sampled_from([0, 1, 2, 3, 4, 5, 7, 1.0, True]),
                             label=name) for name in names)
    assert _built(cls.from_fields, cls, values) == _built(cls, cls, values)


def test_shared_eq_hash_repr_are_the_dataclass_ones(all_command_vectors):
    """Commands are records (armctl/core/records.py: __eq__, __hash__ and __repr__ shared; the dataclass module
    compiles each generated method separately); they answer as the generated ones would, on
    every golden command, against a frozen dataclass with the same fields."""
    import dataclasses

    commands = [vector.obj for vector in all_command_vectors]
    assert len({type(c) for c in commands}) == 15
    for command in commands:
        cls = type(command)
        twin_cls = dataclasses.make_dataclass(cls.__qualname__, [f.name for f in dataclass_fields(cls)], frozen=True)
        twin = twin_cls(**command.fields())
        assert repr(command) == repr(twin)
        assert hash(command) == hash(twin)
        for other in commands:
            same = other == command
            assert same == (type(other) is cls and twin_cls(**other.fields()) == twin)
            assert (other != command) is not same
        assert command.__eq__(twin) is NotImplemented
        with pytest.raises(dataclasses.FrozenInstanceError):
            command.extra = 1
