"""Partitioned Runge-Kutta steps and compositions of any fixed-step basis (user definitions).

**Partitioned RK** ([HLW] II.2.2): when the problem's structure makes every stage explicit and the
stages can be ordered so that each needs only those before it (:func:`stage_order`), the step is
written out in that order (each stage evaluates one block: half an f-evaluation); otherwise the
Newton template templates/prk.py solves the stage equations, with the tableaus as module
constants (AU, BU, AV, BV and IN_U, the block of each component). An implicit RK method is the
case Â = A on one block.

**Compositions** ([HLW] II.4): :func:`write_composition`.
"""
from __future__ import annotations

from gnibench.methods.assembly.source import INTERNAL, copy
from gnibench.methods.assembly.templates import prk
from gnibench.methods.tableau import lit


def stage_order(au, av, bu, bv, explicit_u: bool, explicit_v: bool):
    """The stages ("K", i) (block u) and ("L", i) (block v) the step needs, in an order where each
    needs only those before it; None when there is none (the stage equations are implicit)."""
    s = len(bu)

    def deps(node):
        kind, i = node
        need_u = kind == "L" or not explicit_u
        need_v = kind == "K" or not explicit_v
        out = [("K", j) for j in range(s) if need_u and au[i][j] != 0]
        return out + [("L", j) for j in range(s) if need_v and av[i][j] != 0]

    order, state = [], {}

    def visit(node) -> bool:
        if state.get(node) == "done":
            return True
        if state.get(node) == "open":
            return False
        state[node] = "open"
        if not all(visit(d) for d in deps(node)):
            return False
        state[node] = "done"
        order.append(node)
        return True

    final = [("K", j) for j in range(s) if bu[j] != 0] + [("L", j) for j in range(s) if bv[j] != 0]
    return order if all(visit(n) for n in final) else None


def _comb(base: str, idx: int, terms) -> str:
    parts = " + ".join(f"{lit(c)} * {name}[{idx}]" for c, name in terms if c != 0)
    return f"{base}[{idx}] + h * ({parts})" if parts else f"{base}[{idx}]"


def _explicit_source(n, u_idx, order, au, av, bu, bv, explicit_u, explicit_v) -> str:
    lines = [f"\n{INTERNAL}\ndef step(y, h, par, ws):"]
    for kind, i in order:
        need_u = kind == "L" or not explicit_u
        need_v = kind == "K" or not explicit_v
        comps = []
        for idx in range(n):
            if idx in u_idx:
                terms = [(au[i][j], f"K{j}") for j in range(len(bu))] if need_u else []
            else:
                terms = [(av[i][j], f"L{j}") for j in range(len(bv))] if need_v else []
            comps.append(_comb("y", idx, terms))
        lines.append(f"    {kind}{i} = f(({', '.join(comps)}{',' if n == 1 else ''}), par)")
    final = [_comb("y", idx, [(bu[j], f"K{j}") for j in range(len(bu))] if idx in u_idx else
                   [(bv[j], f"L{j}") for j in range(len(bv))]) for idx in range(n)]
    lines.append(f"    return ({', '.join(final)}{',' if n == 1 else ''}), "
                 f"{0.5 * len(order)!r}, 0.0, STATUS_OK")
    return f"\n{INTERNAL}\ndef make_ws():\n    return 0\n" + "\n".join(lines) + "\n"


def write_prk(u: tuple, v: tuple | None = None):
    """The generator of a partitioned RK step (``v`` None: an implicit RK method on the whole
    state, tableau ``u``); coefficients as exact numbers, written as their nearest doubles."""
    (au, bu), (av, bv) = u, v or u

    def generate(ctx) -> str:
        n = ctx.n
        u_idx = set(range(n)) if v is None else set(ctx.meta["u_idx"])
        if v is not None:
            order = stage_order(au, av, bu, bv, ctx.explicit_u, ctx.explicit_v)
            if order is not None:
                return _explicit_source(n, u_idx, order, au, av, bu, bv, ctx.explicit_u,
                                        ctx.explicit_v)

        def mat(a):
            return "(" + ", ".join("(" + ", ".join(lit(x) for x in row) + ",)" for row in a) + ",)"

        consts = [f"S = {len(bu)}", f"AU = {mat(au)}", f"AV = {mat(av)}",
                  "BU = (" + ", ".join(lit(x) for x in bu) + ",)",
                  "BV = (" + ", ".join(lit(x) for x in bv) + ",)",
                  "IN_U = (" + ", ".join(str(i in u_idx) for i in range(n)) + ",)"]
        return "\n" + "\n".join(consts) + "\n" + copy(prk.make_ws) + copy(prk.step)

    return generate


def write_composition(basis, gammas):
    """Ψ_h = Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h}: the basis's step, called with γ_k h in turn. The basis's
    step is compiled in a kernel module of its own (its writer's text unchanged, so a basis that is
    itself a composition nests): ``ctx.extra["step_module"]`` assembles it for the cell's problem
    and field and gives its name; ``basis_step`` and ``basis_make_ws`` are bound to its functions."""
    def write(ctx) -> str:
        module = ctx.extra["step_module"](basis)
        lines = [f"\n{INTERNAL}\ndef step(y, h, par, ws):", "    nf = 0.0", "    nj = 0.0"]
        for g in gammas:
            lines += [f"    y, a, b, s = basis_step(y, {lit(g)} * h, par, ws)", "    nf += a",
                      "    nj += b", "    if s != STATUS_OK:", "        return y, nf, nj, s"]
        lines.append("    return y, nf, nj, STATUS_OK")
        return (f"\nimport sys as _sys\n\nbasis_step = _sys.modules[{module!r}].step\n"
                f"basis_make_ws = _sys.modules[{module!r}].make_ws\n"
                f"\n{INTERNAL}\ndef make_ws():\n    return basis_make_ws()\n"
                + "\n".join(lines) + "\n")
    return write
