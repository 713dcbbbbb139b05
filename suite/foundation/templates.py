"""Code templates: how plain Python functions become the numba source of a cell's module.

Methods, modifiers and problems describe their compiled parts as template functions (plain, lintable
Python whose free names are bound in the generated module, see :mod:`gnibench.methods.kernels.free`)
or as generated text. This module holds the few pieces every generator shares: the copy of a
template's source (:func:`template`), the tuple/array helpers of a state of N components
(:func:`tuple_helpers`) and the :class:`Context` a generator may read. The assembly of a cell's
module lives above, in :mod:`gnibench.suite.cell.codegen`.
"""
from __future__ import annotations

import functools
import inspect
import re
import textwrap
from dataclasses import dataclass, field
from typing import Any


@dataclass
class Context:
    """What a method or modifier generator may know about the cell it generates code for."""

    n: int
    meta: dict
    values: dict
    modified: bool
    explicit_u: bool
    explicit_v: bool
    extra: dict = field(default_factory=dict)
    problem: Any = None        # the problem record, for methods built from its model (generating-function4)
    #: the text is only hashed (the kernel key that groups cells, suite/cell/compiled.py): a part
    #: that is a costly but deterministic function of named inputs may stand as their digest
    keyed: bool = False


def template(func, rename: dict[str, str] | None = None, inline: bool = False) -> str:
    """Source of a template function, decorated for numba, with identifiers renamed.

    ``inline``: marked ``inline='always'``, the function is written into its callers' source when
    the module is cached (:mod:`gnibench.suite.foundation.inline`; numba's own IR inlining is
    the fallback where it cannot be) instead of being compiled on its own: for the small pieces
    of a driver loop (a controller's update, a sample's row, Newton's parts), whose separate
    compilation would cost more than their code. It must then have one ``return``, its last
    statement."""
    return _template(func, tuple((rename or {}).items()), inline)


@functools.cache
def _template(func, rename: tuple[tuple[str, str], ...], inline: bool) -> str:
    """:func:`template`, made once per process for each function, renaming and marking (a cell's
    module text is rebuilt for every cell a runner plans, e.g. the 192 initial values of [HLW]
    Fig 1.1: the renames were three quarters of it)."""
    src = _source(func)
    for old, new in rename:
        src = re.sub(rf"\b{re.escape(old)}\b", new, src)
    return ("\n@njit(cache=True, inline='always')\n" if inline else "\n@njit(cache=True)\n") + src


@functools.cache
def _source(func) -> str:
    """The dedented source of a function (read once per process: inspect tokenizes the file)."""
    return textwrap.dedent(inspect.getsource(func))


def tuple_helpers(n: int) -> str:
    """to_tuple, shifted, store: conversions between the tuple state and arrays, unrolled over the
    N components and marked for inlining (:mod:`gnibench.suite.foundation.inline`): written at
    their call sites, they are not compiled on their own (``store`` was compiled once per row
    argument type, 4 times in a dopri5 cell)."""
    items = ", ".join(f"a[{i}]" for i in range(n))
    shifted = ", ".join(f"y[{i}] + Z[j, {i}]" for i in range(n))
    comma = "," if n == 1 else ""
    return f'''
@njit(cache=True, inline='always')
def to_tuple(a):
    return ({items}{comma})

@njit(cache=True, inline='always')
def shifted(y, Z, j):
    return ({shifted}{comma})

{store_source("store", n)}'''


def store_source(name: str, width: int) -> str:
    """``name(t, A, j)``: row j of A set to the tuple t of ``width`` components, unrolled and
    marked for inlining."""
    body = "".join(f"    A[j, {i}] = t[{i}]\n" for i in range(width)) or "    pass\n"
    return f"@njit(cache=True, inline='always')\ndef {name}(t, A, j):\n{body}"
