"""Dataclasses that cost almost nothing at import: ``record`` is ``dataclass`` whose methods are
shared or compiled on first use instead of compiled for each class at import.

Strategy: the dataclass module writes the source of every generated method of every class and
compiles it at import — for a frozen class six methods, ~0.8 ms — and a short command such as
``armctl lint small.txt`` imports some forty classes and builds a few of them.  ``record`` asks
the dataclass module for the fields only (``init=False, eq=False, repr=False``, not frozen: no
method generated) and then gives the class:

  __init__   the one per-class method: its source is the generated one's (positional or
             keyword, defaults, ``default_factory``, ``__post_init__``; a frozen class assigns
             through ``object.__setattr__``), compiled the first time the class is built or
             ``inspect.signature`` asks for it;
  __setattr__, __delattr__ (frozen)  refuse a field or any name on the class itself with
             ``FrozenInstanceError``, as generated; ``__getstate__``/``__setstate__`` for a
             frozen class with slots (pickle, copy), as dataclass adds them;
  __eq__, __hash__, __repr__  shared functions reading the fields through one ``attrgetter``:
             equal only to an instance of the very same class whose compared fields are equal
             (as tuples, or field by field from Python 3.13, as that Python's dataclass does),
             the hash of the hashed fields' tuple (a mutable class is unhashable, as with
             ``eq=True``), ``Name(field=value, …)`` over the fields shown in repr.

``__dataclass_params__`` says what the class is (frozen or not, with init, repr and eq), so
``dataclasses.fields``, ``replace`` and subclassing rules see an ordinary dataclass.  A method
the class body defines itself is kept, as ``dataclass`` does.  A class with an ``InitVar`` or
a keyword-only field, or one extending a frozen dataclass, is simply handed to ``dataclass``
(none of armctl's records is).
tests/test_records.py holds all of this to twins made by ``dataclass``.
"""

from __future__ import annotations

import operator
import sys
from dataclasses import MISSING, FrozenInstanceError, dataclass, field, fields
from types import MethodType

__all__ = ["record"]

# How the running Python's dataclass compares: as tuples of the fields up to 3.12 (so a field
# holding one NaN object equals itself), field by field from 3.13 (an instance equals itself,
# and NaN never equals NaN).  A record compares as a dataclass of the same Python does.
_FIELD_BY_FIELD_EQ = sys.version_info >= (3, 13)


def _getter(names: tuple):
    """``instance`` → the tuple of those attributes (the generated methods compare such tuples)."""
    if len(names) > 1:
        return operator.attrgetter(*names)
    if names:
        name = names[0]
        return lambda self: (getattr(self, name),)
    return lambda self: ()


class _Factory:
    """A parameter's default when its field has a default_factory (as generated: ``<factory>``)."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "<factory>"


_FACTORY = _Factory()


def _init_function(cls, frozen: bool):
    """The dataclass ``__init__`` of ``cls``, compiled now (see the module docstring)."""
    namespace = {"_FACTORY": _FACTORY, "_set": object.__setattr__}
    params, body = ["self"], []
    for f in fields(cls):
        if f.init:
            if f.default is not MISSING:
                namespace[f"_d_{f.name}"] = f.default
                params.append(f"{f.name}=_d_{f.name}")
            elif f.default_factory is not MISSING:
                namespace[f"_f_{f.name}"] = f.default_factory
                params.append(f"{f.name}=_FACTORY")
            else:
                params.append(f.name)
            value = f"_f_{f.name}() if {f.name} is _FACTORY else {f.name}" if f.default_factory is not MISSING else f.name
        elif f.default is not MISSING:
            namespace[f"_d_{f.name}"] = f.default
            value = f"_d_{f.name}"
        elif f.default_factory is not MISSING:
            namespace[f"_f_{f.name}"] = f.default_factory
            value = f"_f_{f.name}()"
        else:
            continue  # init=False without a default: __post_init__ sets it
        body.append(f"    _set(self, {f.name!r}, {value})" if frozen else f"    self.{f.name} = {value}")
    if hasattr(cls, "__post_init__"):
        body.append("    self.__post_init__()")
    source = f"def __init__({', '.join(params)}):\n" + ("\n".join(body) or "    pass") + "\n"
    exec(compile(source, f"<{cls.__qualname__}.__init__>", "exec"), namespace)  # noqa: S102 - our own source
    function = namespace["__init__"]
    function.__qualname__ = f"{cls.__qualname__}.__init__"
    function.__annotations__ = {**{f.name: f.type for f in fields(cls) if f.init}, "return": None}  # as generated
    return function


class _FirstBuild:
    """A record's ``__init__`` until the class is first built (or its signature asked for):
    then the real one is compiled, becomes the class's ``__init__`` and runs."""

    __slots__ = ("cls", "frozen")

    def __init__(self, cls, frozen: bool) -> None:
        self.cls, self.frozen = cls, frozen

    def _compiled(self):
        function = _init_function(self.cls, self.frozen)
        self.cls.__init__ = function
        return function

    def __get__(self, instance, owner=None):
        return self if instance is None else MethodType(self, instance)

    def __call__(self, instance, *args, **kwargs) -> None:
        self._compiled()(instance, *args, **kwargs)

    @property
    def __signature__(self):  # inspect.signature(cls), help(cls): the real parameters
        from inspect import signature

        return signature(self._compiled())


TYPE_CHECKING = False  # true for type checkers; typing is not imported at run time for this
if TYPE_CHECKING:
    from typing import dataclass_transform
else:
    def dataclass_transform(**_options):  # type checkers only: at run time the decorator as it is
        return lambda function: function


@dataclass_transform(frozen_default=True, field_specifiers=(field,))
def record(cls=None, /, *, frozen: bool = True, slots: bool = False):
    """``@dataclass(frozen=frozen, slots=slots)``, its methods shared or compiled on first use."""

    def wrap(cls):
        own = set(cls.__dict__)
        annotations = cls.__dict__.get("__annotations__", {})
        frozen_base = any(getattr(getattr(base, "__dataclass_params__", None), "frozen", False) for base in cls.__mro__[1:])
        if frozen_base or any("InitVar" in str(a) or "KW_ONLY" in str(a) for a in annotations.values()):
            return dataclass(frozen=frozen, slots=slots)(cls)  # what record does not do itself
        cls = dataclass(slots=slots, init=False, eq=False, repr=False)(cls)
        every = fields(cls)
        if any(f.kw_only for f in every):  # pragma: no cover - field(kw_only=True): dataclass does it
            raise TypeError(f"record {cls.__qualname__}: keyword-only fields are not supported; use dataclass")
        names = frozenset(f.name for f in every)
        compared = _getter(tuple(f.name for f in every if f.compare))
        hashed = _getter(tuple(f.name for f in every if (f.compare if f.hash is None else f.hash)))
        shown = tuple(f.name for f in every if f.repr)
        shown_values = _getter(shown)

        if _FIELD_BY_FIELD_EQ:
            def __eq__(self, other):
                if self is other:
                    return True
                if other.__class__ is self.__class__:
                    equal = True  # ``self.a == other.a and self.b == other.b …``, as generated
                    for mine, theirs in zip(compared(self), compared(other)):
                        equal = mine == theirs
                        if not equal:
                            return equal
                    return equal
                return NotImplemented
        else:
            def __eq__(self, other):
                if other.__class__ is self.__class__:
                    return compared(self) == compared(other)
                return NotImplemented

        def __hash__(self):
            return hash(hashed(self))

        def __repr__(self):
            values = shown_values(self)
            return f"{self.__class__.__qualname__}({', '.join(f'{n}={v!r}' for n, v in zip(shown, values))})"

        def __setattr__(self, name, value):
            if type(self) is cls or name in names:
                raise FrozenInstanceError(f"cannot assign to field {name!r}")
            super(cls, self).__setattr__(name, value)

        def __delattr__(self, name):
            if type(self) is cls or name in names:
                raise FrozenInstanceError(f"cannot delete field {name!r}")
            super(cls, self).__delattr__(name)

        def __getstate__(self):
            return [getattr(self, f.name) for f in fields(self)]

        def __setstate__(self, state):
            for f, value in zip(fields(self), state):
                object.__setattr__(self, f.name, value)

        methods = {"__init__": _FirstBuild(cls, frozen), "__repr__": __repr__}
        if "__eq__" not in own:
            methods["__eq__"] = __eq__
            if "__hash__" not in own:
                methods["__hash__"] = __hash__ if frozen else None
        if frozen:
            if "__setattr__" in own or "__delattr__" in own:
                raise TypeError(f"record {cls.__qualname__}: a frozen record cannot define __setattr__/__delattr__")
            methods.update(__setattr__=__setattr__, __delattr__=__delattr__)
            if slots:
                methods.update(__getstate__=__getstate__, __setstate__=__setstate__)
        for name, method in methods.items():
            if name in own and name not in ("__hash__", "__setattr__", "__delattr__"):
                continue
            if method is not None and name != "__init__":
                method.__qualname__ = f"{cls.__qualname__}.{name}"
            setattr(cls, name, method)
        params = cls.__dataclass_params__  # what the class is, for fields(), replace() and subclasses
        params.init = params.repr = params.eq = True
        params.frozen = frozen
        return cls

    return wrap if cls is None else wrap(cls)
