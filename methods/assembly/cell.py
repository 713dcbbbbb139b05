"""A cell's kernel module, put together: what :func:`gnibench.methods.assembly.assemble` writes.

The text of a cell's module, in order (each part's writer or template named):

1. the header: numba's ``njit`` and the four decorators (source.py), the constants ``N``,
   ``NEWTON_MAXIT``, ``COMPENSATED`` (the summation mode, methods/summation.py), the slots and
   status codes (templates/slots.py) and the event constants (sections.py);
2. the problem's functions, generated from its sympy model (problems/codegen.py), and its
   ``post_step`` (the identification map, or the identity: fields.py);
3. the helpers: tuple/array conversions (source.py), the compensated-summation carries
   (:func:`carry_source`), the linear algebra and Newton's stopping rule (templates/linalg.py,
   templates/newton.py), ``record_row`` (templates/rows.py);
4. the field ``f``/``fjac`` with the field modifiers' terms and the step modifiers' ``project``
   (fields.py, steps/modifiers.py);
5. the method's step: its family's writer (``Method.generate``, steps/<family>.py), which for an
   adaptive cell also writes the attempt, the controller and the continuous extension;
6. the driver for the output (drivers.py), unless ``output`` is None.

``par`` (built in suite/cell/compiled.py) holds the problem's model parameters, then each
modifier's numbers, then the method's runtime options (``Method.runtime``), then its runtime data
(``Method.runtime_data``): the writers read the offsets from ``Context.extra``.
"""
from __future__ import annotations

from dataclasses import replace

from gnibench.methods.assembly import loading
from gnibench.methods.assembly.bindings import driver_kind
from gnibench.methods.assembly.drivers import write_driver
from gnibench.methods.assembly.fields import write_field, write_post_step
from gnibench.methods.assembly.sections import event_constants, henon_source, locate_all_source
from gnibench.methods.assembly.source import (
    DECORATORS,
    ENTRY,
    INLINE,
    Context,
    constants,
    copy,
    store_source,
    tuple_helpers,
)
from gnibench.methods.assembly.templates import linalg, newton, rows
from gnibench.methods.assembly.templates.slots import slot_constants


def header(n: int, newton_maxit: int = 50, compensated: bool = False) -> str:
    return ("# a kernel module written by gnibench (methods/assembly); do not edit\n"
            "import math\n\nimport numpy as np\nfrom numba import njit\n" + DECORATORS
            + constants(N=n, NEWTON_MAXIT=int(newton_maxit), COMPENSATED=bool(compensated))
            + slot_constants() + event_constants())


def carry_source(n: int) -> str:
    """The helpers of ``sum=compensated`` (methods/summation.py), in every cell's module:

    ``carry_sum(a, e, d) -> (s, e')``: a + (e + d) rounded, and the exact error of that addition;
    ``carry_add(y, e, d) -> (y', e')``: the same over the n components of tuples;
    ``carry_apply(y, e)``: y + e rounded (a point that starts from the carried state);
    ``carry_zero(y)``: a zero carry of y's shape."""
    comma = "," if n == 1 else ""
    lines = [f"\n{INLINE}\ndef carry_sum(a, e, d):",
             "    # [HLW] VIII.5 Alg. 5.1 with Knuth's TwoSum: s + err == a + (e + d) exactly",
             "    x = e + d", "    s = a + x", "    b = s - a",
             "    return s, (a - (s - b)) + (x - b)",
             f"\n{INLINE}\ndef carry_add(y, e, d):"]
    for i in range(n):
        lines.append(f"    s{i}, c{i} = carry_sum(y[{i}], e[{i}], d[{i}])")
    lines.append(f"    return ({', '.join(f's{i}' for i in range(n))}{comma}), "
                 f"({', '.join(f'c{i}' for i in range(n))}{comma})")
    lines += [f"\n{INLINE}\ndef carry_apply(y, e):",
              f"    return ({', '.join(f'y[{i}] + e[{i}]' for i in range(n))}{comma})",
              f"\n{INLINE}\ndef carry_zero(y):",
              f"    return ({', '.join('0.0' for _ in range(n))}{comma})"]
    return "\n".join(lines) + "\n"


def context(problem, method, keyed: bool = False) -> tuple[Context, dict, list[int]]:
    """The writers' context for a cell, the problem's metadata and the modifiers' offsets in
    ``par``."""
    from gnibench.problems.codegen import problem_meta

    meta = problem_meta(problem.record)
    fields = [m for m in method.modifiers if m.record.kind == "field"]
    offsets = []
    off = len(problem.record.model_params)
    for m in method.modifiers:
        offsets.append(off)
        off += m.record.runtime_size(m.values)
    runtime = method.base.record.runtime
    par_at = {name: off + i for i, name in enumerate(runtime)}
    ctx = Context(n=meta["n"], meta=meta, values=method.base.values, modified=bool(fields),
                  explicit_u=meta["explicit_u"] and not fields,
                  explicit_v=meta["explicit_v"] and not fields, problem=problem.record,
                  keyed=keyed, extra={"par_at": par_at, "data_at": off + len(runtime)})
    return ctx, meta, offsets


def cell_text(problem, method, output: str | None = "samples", keyed: bool = False) -> str:
    """The text of a cell's module (the module docstring); ``keyed``: only hashed (the kernel key,
    :attr:`Context.keyed`: nothing is imported, a costly part may stand as its digest)."""
    from gnibench.methods.summation import compensated
    from gnibench.problems.codegen import problem_code

    ctx, meta, offsets = context(problem, method, keyed)
    ctx.extra["step_module"] = lambda basis: step_module(problem, method, basis, keyed)
    n = meta["n"]
    values = method.base.values
    text = [header(n, values.get("newton_maxit", 50), compensated(values)),
            problem_code(problem.record)[0], write_post_step(problem.record),
            tuple_helpers(n), carry_source(n), copy(linalg.lu_solve, INLINE),
            copy(newton.newton_done, INLINE), copy(rows.record_row, INLINE),
            write_field(ctx, method.modifiers, offsets), method.base.record.generate(ctx)]
    if output is not None:
        # a section driver of an unchanged field calls the problem's own Hénon locator
        shared = ("" if ctx.modified or not problem.record.sections
                  else loading.module_name(problem_text(problem), "problem"))
        text.append(write_driver(driver_kind(method), output, n, shared))
    return "\n".join(text)


def step_module(problem, method, basis, keyed: bool = False) -> str:
    """The name of a module holding the step of ``basis`` (a method record) for the cell's
    problem and field, with the cell's option values (a composition's basis,
    steps/prk.py ``write_composition``); imported unless ``keyed``."""
    base = replace(method.base, record=basis)
    sub = replace(method, base=base)
    text = cell_text(problem, sub, None, keyed)
    if not keyed:
        loading.load(text, "cell")
    return loading.module_name(text, "cell")


def problem_text(problem) -> str:
    """The text of a problem's own module: its generated functions (field, Jacobian, integrals
    and gradients, sections) and ``eval_invariants``, shared by every cell of the problem to
    evaluate the first integrals at the samples (compiled cells, external engines, transforms),
    and, with a section, Hénon's locator on its base field and the section scans."""
    from gnibench.problems.codegen import problem_code

    ptext, meta = problem_code(problem.record)
    n, q = meta["n"], len(meta["integrals"])
    parts = [header(n), ptext, tuple_helpers(n), store_source("store_integrals", q),
             copy(rows.eval_invariants, ENTRY)]
    if problem.record.sections:
        parts += [henon_source(n, "base_f"), locate_all_source()]
    return "\n".join(parts)
