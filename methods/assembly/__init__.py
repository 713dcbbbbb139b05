"""Kernel assembly: how a cell (problem x modifiers x method x output) becomes compiled code.

One entry point, :func:`assemble`, writes the text of a cell's kernel module, stores it in the
kernel cache and imports it; numba compiles each function on its first call (and caches the ones
Python calls on disk). The rooms, in the order a module's text is put together
(:mod:`~gnibench.methods.assembly.cell`):

=================  ===============================================================================
``source.py``      the pieces of text: the four decorators by role (``@entry``, ``@shared``,
                   ``@inline``, ``@internal``), templates copied verbatim, alias lines, constants
``templates/``     plain Python functions copied into modules: the drivers' loops (``fixed.py``,
                   ``adaptive.py``), their samples and crossings (``sampling.py``, ``events.py``,
                   ``rows.py``), the state's slots (``slots.py``), the families' Newton kernels
                   and controllers (``irk.py``, ``prk.py``, ``partitioned.py``, ``genfun.py``,
                   ``pair.py``, ``odex.py``), linear algebra (``linalg.py``, ``newton.py``)
``steps/``         the step writers, one per family (``erk.py``, ``pair.py`` with ``dense.py``,
                   ``odex.py``, ``irk.py``, ``partitioned.py``, ``prk.py``, ``lie_poisson.py``,
                   ``genfun.py``), and the modifiers' terms (``modifiers.py``)
``fields.py``      the field ``f``/``fjac`` with the field modifiers, the step modifiers'
                   ``project``, the problem's ``post_step``
``drivers.py``     the driver of a module: its loop, its flags, the parts of its output
``sections.py``    Hénon's locator written out, the section drivers' parts
``bindings.py``    the binding tables: per driver kind and output, and per family, who binds the
                   names the templates leave free (a new driver kind or family starts here)
``cell.py``        the order of the parts; a problem's own module
``loading.py``     the module's file in the kernel cache, its checksum, its import; numba's files
=================  ===============================================================================

How the pieces meet: a **step** is written by the method's family writer (``Method.generate``);
a **driver** is a loop template copied with its output's flags as module constants (one driver
per module, so numba compiles only its own branches); **dense output** is the pair's continuous
extension (steps/dense.py) used by the ``dense`` and ``section_dense`` outputs; a **section**
adds the crossing test and a locator; a **modifier** adds a term to ``f`` (observer, penalty) or a
map to ``project`` (projection); the **summation mode** (``sum=compensated``) sets
``COMPENSATED`` and makes the writers emit ``step_sum``, which the loops call instead of
``step``. Nothing edits a module's text after it is written: small functions are written into
their callers by numba's inliner (``inline='always'``, numba's public option).
"""
from __future__ import annotations

from types import ModuleType


def assemble(problem, method, output: str | None = "samples") -> ModuleType:
    """The kernel module of a cell, imported (written to the kernel cache first if needed).

    Parameters
    ----------
    problem : Bound
        The problem with its option values.
    method : MethodConfig
        The base method and its modifiers, with their option values.
    output : str or None
        The output of the cell's driver kind (:data:`.bindings.DRIVERS`: ``samples``, ``grid``,
        ``section``; adaptive cells also ``dense`` and ``section_dense``), or None for a module
        without a driver (the field, the step, the continuous extension).

    A cell of a problem with a section has its problem's module imported first (a cell of its
    unchanged field calls that module's Hénon locator).
    """
    from gnibench.methods.assembly import cell, loading

    if problem.record.sections:
        assemble_problem(problem)
    return loading.load(cell.cell_text(problem, method, output), "cell")


def assemble_problem(problem) -> ModuleType:
    """A problem's own module (its functions, ``eval_invariants``, the section scans), imported."""
    from gnibench.methods.assembly import cell, loading

    return loading.load(cell.problem_text(problem), "problem")


def kernel_text(problem, method, output: str | None = "samples") -> str:
    """The text :func:`assemble` would write, for hashing only (a part sympy takes seconds to make
    stands as the digest of what it is made from; nothing is imported)."""
    from gnibench.methods.assembly import cell

    return cell.cell_text(problem, method, output, keyed=True)
