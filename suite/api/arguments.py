"""The one schema of the Python API's arguments: every public function checks its arguments here,
before any work, and a bad one raises :class:`~gnibench.suite.foundation.errors.UserError` with
one line naming the function, the argument, the bad value and what is allowed.

The schema is the functions' own annotations, read by :func:`api_function` and made strict with
pydantic (:class:`pydantic.TypeAdapter` per argument):

=====================  =========================================================================
annotation             accepted
=====================  =========================================================================
``int``                a Python or numpy integer (not a bool, not a float such as ``10.0``)
``float``              a Python or numpy integer or float (not a bool, not a string)
``bool``               ``True`` or ``False`` (also ``numpy.bool_``; not ``"yes"``, not 1)
``str``                a string
``Path``               a non-empty string or :class:`os.PathLike` (given back as a Path)
``list[X]``            a list or tuple of X (not a string, not a set)
``dict``               a dict
a class                an instance of it (a parsed problem, a parsed method, ...)
``X | None``           X, or None
=====================  =========================================================================

Only the types are checked here; the values (ranges, known ids, options that exclude each other)
are checked by the library below, with the same messages as the command line's.
"""
from __future__ import annotations

import functools
import inspect
import os
import reprlib
import types
import typing
from pathlib import Path

from gnibench.suite.foundation.errors import UserError

__all__ = ["api_function", "allowed_text"]

_SHOW = reprlib.Repr()
_SHOW.maxstring, _SHOW.maxother, _SHOW.maxlist, _SHOW.maxdict = 60, 60, 6, 4


def _scalar(value):
    """numpy scalars as the Python numbers (and bools, strings) they hold."""
    if type(value).__module__ == "numpy" and hasattr(value, "item") and getattr(value, "ndim", 1) == 0:
        return value.item()
    return value


def _sequence(value):
    """A tuple as a list (a list of X takes both)."""
    return list(value) if isinstance(value, tuple) else value


def _path(value):
    if isinstance(value, (str, os.PathLike)):
        text = os.fspath(value)
        if isinstance(text, str) and text.strip():
            return Path(text)
    raise ValueError("not a path")


#: what an API annotation that names one of gnibench's records allows, in words
_CLASS_WORDS = {"Bound": "a parsed problem (gnibench.suite.cell.spec.parse_problem)",
                "MethodConfig": "a parsed method (gnibench.suite.cell.spec.parse_method)"}
_NAMES = {int: "an integer", float: "a number", bool: "True or False", str: "a string",
          Path: "a path (str or os.PathLike)", dict: "a dict", type(None): "None"}


def _arg(tp) -> tuple[object, str]:
    """The strict pydantic type of an annotation, and what it allows, in words."""
    from typing import Annotated

    from pydantic import BeforeValidator, Strict

    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        members = [_arg(t) for t in typing.get_args(tp)]
        return (typing.Union[tuple(m[0] for m in members)],
                ", or ".join(m[1] for m in members))
    if origin in (list, typing.get_origin(typing.Sequence[int])):
        (item,) = typing.get_args(tp)
        inner, words = _arg(item)
        return (Annotated[list[inner], BeforeValidator(_sequence), Strict()],
                f"a list of {_plural(words)}")
    if tp in (int, float, bool, str):
        return Annotated[tp, BeforeValidator(_scalar), Strict()], _NAMES[tp]
    if tp is Path:
        return Annotated[Path, BeforeValidator(_path)], _NAMES[Path]
    if tp is dict:
        return Annotated[dict, Strict()], _NAMES[dict]
    if tp is type(None) or tp is None:
        return type(None), "None"
    if tp is typing.Any:
        return typing.Any, "anything"
    if isinstance(tp, type):
        from pydantic import InstanceOf

        return InstanceOf[tp], _CLASS_WORDS.get(tp.__name__, f"a {tp.__name__}")
    raise TypeError(f"no API argument type for {tp!r}")


def _plural(words: str) -> str:
    return {"a string": "strings", "a number": "numbers", "an integer": "integers",
            "a path (str or os.PathLike)": "paths"}.get(words, words)


class _Schema:
    """The arguments of one API function: a pydantic adapter per argument (built on first use,
    so that ``import gnibench`` imports neither pydantic nor what the annotations name)."""

    def __init__(self, fn):
        self.fn = fn
        self.signature = inspect.signature(fn)
        self._adapters: dict[str, tuple] | None = None

    def adapters(self) -> dict[str, tuple]:
        if self._adapters is None:
            from pydantic import ConfigDict, TypeAdapter

            hints = typing.get_type_hints(self.fn, localns=_annotation_names())
            config = ConfigDict(arbitrary_types_allowed=True)
            self._adapters = {}
            for name in self.signature.parameters:
                tp, words = _arg(hints[name])
                self._adapters[name] = (TypeAdapter(tp, config=config)
                                        if tp is not typing.Any else None, words)
        return self._adapters

    def check(self, args, kwargs) -> inspect.BoundArguments:
        from pydantic import ValidationError

        bound = self.signature.bind(*args, **kwargs)
        adapters = self.adapters()
        for name, value in list(bound.arguments.items()):
            adapter, words = adapters[name]
            if adapter is None:
                continue
            try:
                bound.arguments[name] = adapter.validate_python(value)
            except ValidationError as e:
                raise UserError(_line(self.fn.__name__, name, value, words, e)) from None
        return bound


def _line(function: str, name: str, value, words: str, error) -> str:
    """One line: the function, the argument, its bad value (and the bad item of a list)."""
    where = ""
    if isinstance(value, (list, tuple)):
        index = next((loc for err in error.errors() for loc in err["loc"] if isinstance(loc, int)),
                     None)
        if index is not None and index < len(value):
            item = value[index]
            where = f" (item {index}: {_SHOW.repr(item)}, {_kind(item)})"
    kind = "" if where else f" ({_kind(value)})"
    return (f"gnibench.{function}: bad {name} {_SHOW.repr(value)}{kind}{where}; "
            f"allowed: {words}")


def _kind(value) -> str:
    if value is None:
        return "None"
    name = type(value).__name__
    return f"{'an' if name[:1] in 'aeiou' else 'a'} {name}"


def _annotation_names() -> dict:
    """The classes API annotations may name besides the builtins (imported when a function is
    first called)."""
    from gnibench.suite.cell.reference import ReferenceSpec
    from gnibench.suite.cell.spec import MethodConfig
    from gnibench.suite.foundation.params import Bound

    return {"Bound": Bound, "MethodConfig": MethodConfig, "ReferenceSpec": ReferenceSpec,
            "Path": Path}


def api_function(fn):
    """Check the arguments of a public API function against its annotations (the module
    docstring) before it runs; a bad one raises UserError on one line."""
    schema = _Schema(fn)

    @functools.wraps(fn)
    def checked(*args, **kwargs):
        bound = schema.check(args, kwargs)
        return fn(*bound.args, **bound.kwargs)

    checked.schema = schema
    return checked


def allowed_text(fn, name: str) -> str:
    """What an API function's argument allows, in words (for the documentation and tests)."""
    return fn.schema.adapters()[name][1]


def id_list(ids: str | list[str], function: str = "gnibench.verify") -> list[str]:
    """The ids as a list; an empty list (or string) is refused: "all" says every one."""
    chosen = [ids] if isinstance(ids, str) else list(ids)
    if not chosen or any(not i for i in chosen):
        raise UserError(f"{function}: bad ids {ids!r} (empty); allowed: one or more ids, or "
                        f"\"all\"")
    return chosen
