"""Partitioned Runge-Kutta methods and compositions given as data (user definitions).

**Partitioned RK** ([HLW] II.2.2): a tableau (A, b) for the block u of the problem's partition and
(Â, b̂) for v. When the problem's structure makes every stage explicit (a separable Hamiltonian:
f_u does not depend on u, f_v not on v) and the stages can be ordered so that each one needs only
stages before it, the step is unrolled in that order (each stage evaluates one block: half an
f-evaluation, as for the shipped partitioned methods); otherwise Newton solves the stage equations
(kernels/prk.py). An implicit RK method is the case Â = A on one block.

**Compositions** ([HLW] II.4): Ψ_h = Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h} of a registered basis method Φ;
the basis's generated step is renamed ``basis_step`` and called once per γ.

:data:`PRK_FORMS` gives the shipped partitioned methods as partitioned tableaus, so that a
composition of them can be checked by the order conditions of the composed tableau.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from fractions import Fraction as Fr

from gnibench.methods.base import Method
from gnibench.methods.kernels import prk
from gnibench.methods.tableau import lit
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.templates import template

_H = Fr(1, 2)
#: (A_u, b_u), (A_v, b_v) of the shipped partitioned methods ([HLW] (1.9), (1.17); II.2.2)
PRK_FORMS = {
    "symplectic-euler": (([[1]], [1]), ([[0]], [1])),
    "symplectic-euler-adjoint": (([[0]], [1]), ([[1]], [1])),
    "stormer-verlet": (([[_H, 0], [_H, 0]], [_H, _H]), ([[0, 0], [_H, _H]], [_H, _H])),
}


def compose(forms: tuple, gammas) -> tuple:
    """The partitioned tableau of Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h} for a basis given as a partitioned
    tableau ((A, b), (Â, b̂)): stages concatenated, block (k, k) = γ_k A, block (k, l < k) = γ_l 1 bᵀ,
    weights γ_k b (HNW I §II.4, composition of RK methods)."""
    out = []
    for a, b in forms:
        s, m = len(b), len(gammas)
        big = [[0] * (s * m) for _ in range(s * m)]
        for k, g in enumerate(gammas):
            for i in range(s):
                for l in range(k):
                    for j in range(s):
                        big[k * s + i][l * s + j] = gammas[l] * b[j]
                for j in range(s):
                    big[k * s + i][k * s + j] = g * a[i][j]
        out.append((big, [g * x for g in gammas for x in b]))
    return tuple(out)


def _stage_order(au, av, bu, bv, explicit_u: bool, explicit_v: bool):
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
    lines = ["\n@njit(cache=True)\ndef step(y, h, par, ws):"]
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
    return "\n@njit(cache=True)\ndef make_ws():\n    return 0\n" + "\n".join(lines) + "\n"


def generate_prk(u: tuple, v: tuple | None = None):
    """The generator of a partitioned RK step (``v`` None: an implicit RK method on the whole
    state, tableau ``u``); coefficients as exact numbers, written as their nearest doubles."""
    (au, bu), (av, bv) = u, v or u

    def generate(ctx) -> str:
        n = ctx.n
        u_idx = set(range(n)) if v is None else set(ctx.meta["u_idx"])
        if v is not None:
            order = _stage_order(au, av, bu, bv, ctx.explicit_u, ctx.explicit_v)
            if order is not None:
                return _explicit_source(n, u_idx, order, au, av, bu, bv, ctx.explicit_u,
                                        ctx.explicit_v)

        def mat(a):
            return "(" + ", ".join("(" + ", ".join(lit(x) for x in row) + ",)" for row in a) + ",)"

        consts = [f"S = {len(bu)}", f"AU = {mat(au)}", f"AV = {mat(av)}",
                  "BU = (" + ", ".join(lit(x) for x in bu) + ",)",
                  "BV = (" + ", ".join(lit(x) for x in bv) + ",)",
                  "IN_U = (" + ", ".join(str(i in u_idx) for i in range(n)) + ",)"]
        return "\n" + "\n".join(consts) + "\n" + template(prk.make_ws) + template(prk.step)

    return generate


def _renamed(source: str) -> str:
    """The basis's ``step``/``make_ws`` as ``basis_step``/``basis_make_ws``, and a basis that is
    itself a composition one level deeper (``basis_step`` -> ``basis_basis_step``), so that
    compositions nest without two functions of one name."""
    return re.sub(r"\b((?:basis_)*)(step|make_ws)\(", r"basis_\1\2(", source)


def generate_composition(basis: Method, gammas):
    """Ψ_h = Φ_{γ_s h} ∘ … ∘ Φ_{γ_1 h}: the basis's step renamed, called with γ_k h in turn."""
    def generate(ctx) -> str:
        lines = ["\n@njit(cache=True)\ndef step(y, h, par, ws):", "    nf = 0.0", "    nj = 0.0"]
        for g in gammas:
            lines += [f"    y, a, b, s = basis_step(y, {lit(g)} * h, par, ws)", "    nf += a",
                      "    nj += b", "    if s != STATUS_OK:", "        return y, nf, nj, s"]
        lines.append("    return y, nf, nj, STATUS_OK")
        return (_renamed(basis.generate(ctx))
                + "\n@njit(cache=True)\ndef make_ws():\n    return basis_make_ws()\n"
                + "\n".join(lines) + "\n")
    return generate


@dataclass(frozen=True)
class CompositionMethod(Method):
    """A composition of a registered basis method: the basis's structure needs and refusals."""

    basis: Method | None = None

    def check_structure(self, problem, has_modifiers: bool) -> None:
        """The basis's refusal, said of this method (the one the user named)."""
        try:
            self.basis.check_structure(problem, has_modifiers)
        except UserError as e:
            raise UserError(f"method {self.id} (a composition of {self.basis.id}): "
                            f"{e}".replace(f"method {self.basis.id} ", "it ", 1)) from None
