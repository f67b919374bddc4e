"""Dataclasses that cost less at import: ``record`` is ``dataclass`` with __eq__, __hash__ and
__repr__ shared instead of compiled for each class.

Strategy: the dataclass module writes the source of every generated method of every class and
compiles it at import — for a frozen class six methods, ~0.8 ms, and a short command such as
``armctl lint small.txt`` imports some forty of them.  ``record`` lets the dataclass module
generate only what must be per class (__init__, and a frozen class's __setattr__/__delattr__)
and gives the class three shared functions that read its fields through one ``attrgetter``
built at decoration.  They answer as the generated ones do: equal only to an instance of the
very same class whose compared fields are equal, the hash of the hashed fields' tuple (a frozen
class; a mutable one is unhashable, as with ``eq=True``), ``Name(field=value, …)`` over the
fields shown in repr.  A method the class body defines itself is kept, as ``dataclass`` does.
"""

from __future__ import annotations

import operator
from dataclasses import dataclass, fields

__all__ = ["record"]


def _getter(names: tuple):
    """``instance`` → the tuple of those attributes (the generated methods compare such tuples)."""
    if len(names) > 1:
        return operator.attrgetter(*names)
    if names:
        name = names[0]
        return lambda self: (getattr(self, name),)
    return lambda self: ()


def record(cls=None, /, *, frozen: bool = True, slots: bool = False):
    """``@dataclass(frozen=frozen, slots=slots)`` with shared __eq__, __hash__ and __repr__."""

    def wrap(cls):
        own = set(cls.__dict__)
        cls = dataclass(frozen=frozen, slots=slots, eq=False, repr=False)(cls)
        every = fields(cls)
        compared = _getter(tuple(f.name for f in every if f.compare))
        hashed = _getter(tuple(f.name for f in every if (f.compare if f.hash is None else f.hash)))
        shown = tuple(f.name for f in every if f.repr)
        shown_values = _getter(shown)

        def __eq__(self, other):
            if other.__class__ is self.__class__:
                return compared(self) == compared(other)
            return NotImplemented

        def __hash__(self):
            return hash(hashed(self))

        def __repr__(self):
            values = shown_values(self)
            return f"{self.__class__.__qualname__}({', '.join(f'{n}={v!r}' for n, v in zip(shown, values))})"

        if "__eq__" not in own:
            cls.__eq__ = __eq__
            if "__hash__" not in own:
                cls.__hash__ = __hash__ if frozen else None
        if "__repr__" not in own:
            cls.__repr__ = __repr__
        for method in (__eq__, __hash__, __repr__):
            method.__qualname__ = f"{cls.__qualname__}.{method.__name__}"
        return cls

    return wrap if cls is None else wrap(cls)
