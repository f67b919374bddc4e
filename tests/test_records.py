"""armctl/records.py: ``record`` shares __eq__, __hash__ and __repr__ (start-up) and they answer
as the dataclass module's generated ones do — checked against twins made by ``dataclass``."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Optional

import pytest
from hypothesis import given
from hypothesis import strategies as st

from armctl.records import record
from armctl.script.nodes import CodeLine


def _pair(**options):
    frozen, slots = options.get("frozen", True), options.get("slots", False)

    def body():
        class Thing:
            a: float
            b: str
            c: Optional[tuple] = field(default=None, compare=False)
        return Thing

    return record(body(), frozen=frozen, slots=slots), dataclass(frozen=frozen, slots=slots)(body())


OPTIONS = [dict(), dict(slots=True), dict(frozen=False, slots=True), dict(frozen=False)]
values = st.tuples(st.sampled_from([0.0, -0.0, 1.5, float("nan"), float("inf")]), st.sampled_from(["", "x"]),
                   st.sampled_from([None, (1, 2), (3,)]))


@pytest.mark.parametrize("options", OPTIONS, ids=str)
@given(first=values, second=values)
def test_record_answers_as_dataclass(options, first, second):
    ours, theirs = _pair(**options)
    a, b, ta, tb = ours(*first), ours(*second), theirs(*first), theirs(*second)
    assert repr(a) == repr(ta)
    assert (a == b) == (ta == tb) and (a != b) == (ta != tb)
    assert (a == a) == (ta == ta)  # NaN: the tuple comparison's identity check, as generated
    assert a.__eq__(ta) is NotImplemented and a.__eq__(first) is NotImplemented
    if options.get("frozen", True):
        assert hash(a) == hash(ta)
        with pytest.raises(dataclasses.FrozenInstanceError):
            a.a = 2.0
    else:
        assert type(a).__hash__ is None and type(ta).__hash__ is None
        a.a = 2.0
    assert [(f.name, f.compare) for f in dataclasses.fields(ours)] == [(f.name, f.compare) for f in dataclasses.fields(theirs)]


def test_a_method_the_class_defines_is_kept():
    @record
    class Named:
        name: str

        def __repr__(self) -> str:
            return f"<{self.name}>"

    assert repr(Named("x")) == "<x>" and Named("x") == Named("x") and hash(Named("x")) == hash(("x",))


def test_script_nodes_keep_their_semantics():
    """spans is compare=False: a fast-path node (no spans) equals Lark's; a CodeLine is mutable, so unhashable."""
    fast = CodeLine("G", 1, (("X", 1.0),), 1, 3)
    lark = CodeLine("G", 1, (("X", 1.0),), 1, 3, ((4, 6),))
    assert fast == lark and repr(fast).startswith("CodeLine(letter='G'")
    with pytest.raises(TypeError):
        hash(fast)
