"""The registry of registries: records travel between processes as references, not as code.

A record of a registry (a problem, a method, a modifier, a metric) holds callables (its sympy
model, its code generator), which cannot be pickled. A process pool or a Dask worker needs the
typed cell all the same, so every record class mixes in :class:`Registered`: a record pickles as
``(lookup, kind, id, origin)`` and is looked up again in its registry when it is unpickled (the
same object as the registry's, so identity and the per-process caches keyed by it hold).

The registries themselves live on the floors above (``gnibench.problems``,
``gnibench.methods``, ``gnibench.suite.metrics``); each registers a lookup function here with
:func:`register`, so this floor imports nothing above it. The lookup travels in the pickle by
reference (its module and name), so a worker that has not imported its registry yet imports it
while unpickling.

A record that a process may lack (a user definition loaded from a file or an entry point) carries
an ``origin``: a picklable object with a ``load()`` method that defines the record in this process
(reads the definitions file from the text it carries, or imports the module). When the lookup does
not find the id, the origin is loaded and the lookup tried again.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

#: kind -> lookup(id) -> record or None
_LOOKUPS: dict[str, Callable[[str], Any]] = {}


def register(kind: str, lookup: Callable[[str], Any]) -> None:
    """Declare the registry of a record kind by its lookup function (a module-level function, so
    that it pickles by reference)."""
    _LOOKUPS[kind] = lookup


def kinds() -> tuple[str, ...]:
    """The record kinds registered in this process."""
    return tuple(_LOOKUPS)


def lookup(kind: str, id: str) -> Any:
    """The record ``id`` of the registry ``kind``, or None."""
    fn = _LOOKUPS.get(kind)
    return None if fn is None else fn(id)


def resolve(lookup_fn: Callable[[str], Any], kind: str, id: str, origin: Any = None,
            definition: str | None = None) -> Any:
    """The record of a pickled reference (see the module docstring). ``definition``: the
    sender's text of a user definition; a record of this process defined otherwise (a worker
    that kept an earlier version of an edited file) is defined again from ``origin``."""
    record = lookup_fn(id)
    if origin is not None and (record is None or (
            definition is not None and getattr(record, "definition", None) != definition)):
        origin.load()
        record = lookup_fn(id)
    if record is None:
        where = f" (defined in {origin})" if origin is not None else ""
        raise LookupError(f"no {kind} {id!r} in this process{where}; load its definitions first")
    if definition is not None and getattr(record, "definition", None) != definition:
        raise LookupError(f"the {kind} {id!r} of {origin} is defined differently in this process "
                          f"(its file or module changed during the run)")
    return record


def _by_value(cls, state: dict) -> Any:
    obj = object.__new__(cls)
    obj.__dict__.update(state)
    return obj


class Registered:
    """Mixin of registry records: pickled as a reference to the registry (see the module
    docstring). ``registry`` names the record kind; the record has ``id`` and may have ``origin``.

    A record that is not the one its registry holds under its id (made on the fly, e.g. in a
    test) pickles by value, as a plain dataclass would."""

    registry: ClassVar[str] = ""

    def __reduce__(self):
        fn = _LOOKUPS.get(self.registry)
        origin = getattr(self, "origin", None)
        if fn is not None and (fn(self.id) is self or origin is not None):
            if origin is None:
                return (resolve, (fn, self.registry, self.id, origin))
            return (resolve, (fn, self.registry, self.id, origin,
                              getattr(self, "definition", None)))
        return (_by_value, (type(self), dict(self.__dict__)))
