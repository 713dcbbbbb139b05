"""The field a cell integrates, and the map applied after each of its steps.

``f(y, par)`` is the problem's field ``base_f`` plus the term of each field modifier in the order
given (observer, penalty: ``mod<k>_term``, [B] (2.5), (2.10)); ``fjac(y, par, J)`` its Jacobian
(``base_jac`` plus each modifier's ``mod<k>_jac``). ``project(y, par) -> (y, status)`` chains the
step modifiers (projection: ``proj<k>``) and is the identity without them. The terms are written
by methods/assembly/steps/modifiers.py; ``par`` holds each modifier's numbers after the problem's
(``offsets``; suite/cell/compiled.py builds it).
"""
from __future__ import annotations

from gnibench.methods.assembly.source import ENTRY, INLINE, INTERNAL, copy


def write_field(ctx, modifiers, offsets) -> str:
    """f, fjac and project for the cell's modifiers (Bounds) at their ``par`` offsets."""
    parts = []
    terms = []
    jacs = []
    projections = []
    for k, (mod, off) in enumerate(zip(modifiers, offsets)):
        parts.append(mod.record.generate(ctx, mod.values, k, off))
        if mod.record.kind == "step":
            projections.append(k)
            continue
        terms.append(f"mod{k}_term(y, par)")
        jacs.append(f"    mod{k}_jac(y, par, J)")
    n = ctx.n
    if terms:
        sums = ", ".join(f"z[{i}] + " + " + ".join(f"m{k}[{i}]" for k in range(len(terms)))
                         for i in range(n))
        binds = "\n".join(f"    m{k} = {t}" for k, t in enumerate(terms))
        body = f"    z = base_f(y, par)\n{binds}\n    return ({sums}{',' if n == 1 else ''})"
    else:
        body = "    return base_f(y, par)"
    parts.append(f"\n{ENTRY}\ndef f(y, par):\n{body}\n")
    parts.append(f"\n{ENTRY}\ndef fjac(y, par, J):\n    base_jac(y, par, J)\n" + "\n".join(jacs) + "\n")
    # step modifiers (projection) map each accepted step, in the order given
    chain = "".join(f"    y, s = proj{k}(y, par)\n    if s != STATUS_OK:\n        return y, s\n"
                    for k in projections)
    role = INTERNAL if chain else INLINE
    parts.append(f"\n{role}\ndef project(y, par):\n{chain}    return y, STATUS_OK\n")
    return "".join(parts)


def write_post_step(problem) -> str:
    """The problem's identification map after each step ([B] (8.3)-(8.4)), or the identity."""
    if problem.post_step is not None:
        return copy(problem.post_step, INTERNAL)
    return f"\n{INLINE}\ndef post_step(y, par):\n    return y\n"
