"""armctl/core/records.py: ``record`` builds a dataclass without compiling its methods at import
(start-up) — checked here against twins made by ``dataclass`` itself: construction, equality,
hashing, repr, frozenness, pickling, ``replace`` and subclassing."""

from __future__ import annotations

import copy
import dataclasses
import pickle
from dataclasses import dataclass, field
from typing import Optional

import pytest
from hypothesis import given
from hypothesis import strategies as st

from armctl.core.records import record
from armctl.script.nodes import CodeLine
from armctl.script.source import SourceSpan


def _twins(frozen: bool, slots: bool):
    """The same class body made by ``record`` and by ``dataclass``."""

    def body():
        class Thing:
            a: float
            b: str = "b"
            c: Optional[tuple] = field(default=None, compare=False)
            d: list = field(default_factory=list, repr=False, compare=False)
            e: int = field(default=7, init=False)
            calls: int = field(default=0, init=False, compare=False)

            def __post_init__(self) -> None:
                object.__setattr__(self, "calls", self.calls + 1)

        return Thing

    return record(body(), frozen=frozen, slots=slots), dataclass(frozen=frozen, slots=slots)(body())


OPTIONS = [dict(frozen=True, slots=False), dict(frozen=True, slots=True), dict(frozen=False, slots=True),
           dict(frozen=False, slots=False)]
arguments = st.tuples(st.sampled_from([0.0, -0.0, 1.5, float("nan"), float("inf")]), st.sampled_from(["", "x"]),
                      st.sampled_from([None, (1, 2), (3,)]))


@pytest.mark.parametrize("options", OPTIONS, ids=str)
@given(first=arguments, second=arguments, keywords=st.booleans())
def test_record_answers_as_dataclass(options, first, second, keywords):
    ours, theirs = _twins(**options)
    build = (lambda cls, a, b, c: cls(a, b=b, c=c)) if keywords else (lambda cls, a, b, c: cls(a, b, c))
    a, b, ta, tb = build(ours, *first), build(ours, *second), build(theirs, *first), build(theirs, *second)
    assert repr(a) == repr(ta) and repr(ours(1.0)) == repr(theirs(1.0))
    assert (a == b) == (ta == tb) and (a != b) == (ta != tb)
    assert (a == a) == (ta == ta)  # NaN: the identity check (the tuples' up to 3.12, the instance's from 3.13)
    assert a.__eq__(ta) is NotImplemented and a.__eq__(first) is NotImplemented
    assert (a.d, a.e, a.calls) == (ta.d, ta.e, ta.calls) == ([], 7, 1)
    assert ours(1.0).d is not ours(1.0).d  # default_factory: one list each
    assert (dataclasses.replace(a, b="z") == build(ours, first[0], "z", first[2])) == \
        (dataclasses.replace(ta, b="z") == build(theirs, first[0], "z", first[2]))  # (a NaN field: 3.13 says unequal)
    assert dataclasses.replace(a, b="z").b == "z" and dataclasses.replace(a, b="z").a is a.a
    assert [(f.name, f.compare, f.init) for f in dataclasses.fields(ours)] == \
        [(f.name, f.compare, f.init) for f in dataclasses.fields(theirs)]
    assert dataclasses.is_dataclass(ours) and ours.__dataclass_params__.frozen == options["frozen"]
    if options["frozen"]:
        assert hash(a) == hash(ta)
        attempts = [lambda t: setattr(t, "a", 2.0), lambda t: delattr(t, "a")]
        if not options["slots"]:  # CPython 3.11's own frozen slots class raises TypeError here (its __setattr__
            attempts.append(lambda t: setattr(t, "new", 1))  # names the class slots=True replaced)
        for attempt in attempts:
            with pytest.raises(dataclasses.FrozenInstanceError) as ours_error:
                attempt(a)
            with pytest.raises(dataclasses.FrozenInstanceError) as their_error:
                attempt(ta)
            assert str(ours_error.value) == str(their_error.value)
    else:
        assert ours.__hash__ is None and theirs.__hash__ is None
        a.a = 2.0
        assert a.a == 2.0


@pytest.mark.parametrize("options", OPTIONS, ids=str)
def test_record_pickles_and_copies(options):
    ours, _ = _twins(**options)
    globals()["Thing"] = ours  # pickle finds a class by its qualified name
    ours.__qualname__ = "Thing"
    thing = ours(1.5, "x", (1,))
    for twin in (pickle.loads(pickle.dumps(thing)), copy.copy(thing), copy.deepcopy(thing)):
        assert twin == thing and twin.c == (1,) and type(twin) is ours


@pytest.mark.parametrize("options", OPTIONS, ids=str)
def test_record_signature_is_the_dataclass_one_before_and_after_the_first_build(options):
    import inspect

    ours, theirs = _twins(**options)
    assert str(inspect.signature(ours)) == str(inspect.signature(theirs))  # asked before any build
    ours, _ = _twins(**options)
    ours(1.0)
    assert str(inspect.signature(ours)) == str(inspect.signature(theirs))


def test_record_signature_errors_are_the_dataclass_ones():
    ours, theirs = _twins(frozen=True, slots=False)
    for call in (lambda cls: cls(), lambda cls: cls(1.0, "b", None, [], 5), lambda cls: cls(1.0, e=3)):
        with pytest.raises(TypeError):
            call(ours)
        with pytest.raises(TypeError):
            call(theirs)


def test_a_method_the_class_defines_is_kept_and_a_frozen_subclass_works():
    @record
    class Named:
        name: str

        def __repr__(self) -> str:
            return f"<{self.name}>"

    @dataclass(frozen=True)
    class Longer(Named):
        size: int = 0

    assert repr(Named("x")) == "<x>" and Named("x") == Named("x") and hash(Named("x")) == hash(("x",))
    assert Longer("x", 2).size == 2 and Longer("x") != Named("x")


def test_script_records_keep_their_semantics():
    """spans is compare=False: a fast-path node (no spans) equals Lark's; a CodeLine is mutable,
    so unhashable; a SourceSpan (frozen, slots) is hashable and refuses assignment."""
    fast = CodeLine("G", 1, (("X", 1.0),), 1, 3)
    lark = CodeLine("G", 1, (("X", 1.0),), 1, 3, ((4, 6),))
    assert fast == lark and repr(fast).startswith("CodeLine(letter='G'")
    with pytest.raises(TypeError):
        hash(fast)
    span = SourceSpan("f", 1, 2, 3, "text")
    assert {span: 1}[SourceSpan("f", 1, 2, 3, "text")] == 1 and pickle.loads(pickle.dumps(span)) == span
    with pytest.raises(dataclasses.FrozenInstanceError):
        span.line = 2
    with pytest.raises(dataclasses.FrozenInstanceError):
        span.anything = 2
