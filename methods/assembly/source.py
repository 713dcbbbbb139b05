"""The pieces every kernel module's text is made of: decorators by role, copied templates, aliases.

A kernel module is plain Python text that numba compiles (:mod:`gnibench.methods.assembly`). Its
functions come from two kinds of source, and both end up as ``def`` statements under one of four
decorators, chosen by the function's role and written in the text (no pass edits the text later):

* **templates**: plain functions in :mod:`gnibench.methods.assembly.templates`, copied verbatim
  under their own names by :func:`copy` (their source, read by :mod:`inspect`; no renaming);
* **writers**: functions that write text unrolled for the cell (a tableau's stages over the N
  components, the problem's field from sympy, a modifier's term), in
  :mod:`gnibench.methods.assembly.steps`, :mod:`~gnibench.methods.assembly.fields` and
  :mod:`gnibench.problems.codegen`.

The names a template leaves free are bound in the module by the binding tables
(:mod:`gnibench.methods.assembly.bindings`): defined by a writer or a copied template, or, when the
provider's name differs, by an explicit alias line (:func:`alias`, e.g. ``solve_stages =
stages_newton``).

The roles (every function is compiled with ``error_model='numpy'``: with numba's default each float
division checks for a zero divisor and may raise, so LLVM can neither drop a division whose result
is unused nor schedule it freely: Störmer-Verlet's explicit blocks evaluate f twice and use half of
each, measured 1.5x slower than C on kepler-2d with the check, 0.95x without; results are
bit-identical, and a division by zero yields inf/nan, a ``nonfinite`` or ``newton_failed`` status):

=============  ================================================  ==========================================
decorator      numba options                                     for
=============  ================================================  ==========================================
``@entry``     ``cache=True``                                    what Python calls: the drivers, the field
                                                                 and dense output (tests), the integrals at
                                                                 the samples, the section scans
``@shared``    ``cache=True, inline='always'``                   the problem's functions: called from Python
                                                                 (engines, tests) and written into their
                                                                 compiled callers by numba
``@inline``    ``inline='always'``                               small helpers written into each caller by
                                                                 numba's inliner (a controller's update, a
                                                                 sample's row, Newton's parts)
``@internal``  (none)                                            everything else: compiled with its callers;
                                                                 its machine code is saved in their cache
                                                                 files
=============  ================================================  ==========================================
"""
from __future__ import annotations

import functools
import inspect
import textwrap
from dataclasses import dataclass, field
from typing import Any

ENTRY, SHARED, INLINE, INTERNAL = "@entry", "@shared", "@inline", "@internal"

DECORATORS = '''
entry = njit(cache=True, error_model="numpy")
shared = njit(cache=True, error_model="numpy", inline="always")
inline = njit(error_model="numpy", inline="always")
internal = njit(error_model="numpy")
'''


@dataclass
class Context:
    """What a writer may know about the cell it writes code for."""

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


def copy(func, decorator: str = INTERNAL) -> str:
    """The source of a template function under ``decorator``, unchanged."""
    return f"\n{decorator}\n{_source(func)}"


@functools.cache
def _source(func) -> str:
    """The dedented source of a function (read once per process: inspect tokenizes the file)."""
    return textwrap.dedent(inspect.getsource(func))


def alias(name: str, target: str) -> str:
    """``name = target``: a name a template calls, bound to the function that provides it."""
    return f"\n{name} = {target}\n"


def constants(**values) -> str:
    """``NAME = value`` lines (repr of each value: numba reads module globals as constants)."""
    return "\n" + "".join(f"{k} = {v!r}\n" for k, v in values.items())


def tup(items) -> str:
    """A tuple display of the given item texts (one item: with its trailing comma)."""
    items = list(items)
    return "(" + ", ".join(items) + ("," if len(items) == 1 else "") + ")"


def tuple_helpers(n: int) -> str:
    """to_tuple, shifted, store: conversions between the tuple state and arrays, unrolled over the
    N components and written into their callers (``store`` was compiled once per row argument type,
    4 times in a dopri5 cell)."""
    return (f"\n{INLINE}\ndef to_tuple(a):\n    return {tup(f'a[{i}]' for i in range(n))}\n"
            f"\n{INLINE}\ndef shifted(y, Z, j):\n"
            f"    return {tup(f'y[{i}] + Z[j, {i}]' for i in range(n))}\n"
            + store_source("store", n))


def store_source(name: str, width: int) -> str:
    """``name(t, A, j)``: row j of A set to the tuple t of ``width`` components, unrolled."""
    body = "".join(f"    A[j, {i}] = t[{i}]\n" for i in range(width)) or "    pass\n"
    return f"\n{INLINE}\ndef {name}(t, A, j):\n{body}"
